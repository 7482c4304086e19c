"""hugger.plan_many: many independent plans on a thread pool, in input order, errors per case."""
from __future__ import annotations

import threading
from dataclasses import dataclass, replace

import numpy as np
import pytest

import helpers
import hugger
from helpers import same


@pytest.fixture(scope="module")
def hand():
    return hugger.Hand(fingers=3, links=3, link_length=0.02, link_radius=0.003, palm_radius=0.025, palm_thickness=0.01)


@pytest.fixture(scope="module")
def cases(hand):
    """Six different cases: three objects, two start directions each."""
    objs = [hugger.objects.sphere(0.035, subdivisions=3), hugger.objects.ellipsoid((0.04, 0.035, 0.03), subdivisions=3),
            hugger.objects.box((0.05, 0.045, 0.04), divisions=3)]
    out = []
    for obj in objs:
        for d in ([0.0, 0.0, 1.0], [0.6, 0.0, 0.8]):
            out.append({"hand": hand, "obj": obj, "target": [0.0, 0.0, 0.0],
                        "palm_pose": hugger.look_at(0.17 * np.asarray(d), [0, 0, 0])})
    return out


@pytest.fixture(scope="module")
def sequential(cases):
    return [hugger.plan(c["hand"], c["obj"], c["target"], c["palm_pose"]) for c in cases]


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_results_in_input_order_and_identical_to_sequential(cases, sequential, threads):
    out = hugger.plan_many(cases, threads=threads)
    assert len(out) == len(cases)
    assert all(isinstance(t, hugger.Trajectory) for t in out)
    for t, ref in zip(out, sequential):
        assert same(t, ref)
    assert len({len(t) for t in out}) > 1  # the cases really differ, so order matters


@pytest.mark.parametrize("threads", [2, 3])
def test_cases_sharing_a_noisy_skin_plan_as_in_one_thread(cases, threads):
    # A SensorModel's noise is one stream: read by threads in turn, the plans would depend on
    # which thread asked first. Cases sharing it are planned in input order, one after another.
    def mixed():
        noisy = hugger.skins.SensorModel(cases[0]["obj"], gap_noise=2e-6, seed=3)
        other = hugger.skins.SensorModel(cases[2]["obj"], gap_noise=2e-6, seed=4)
        skins = [noisy, other, None, noisy, other, noisy]
        return [{**c, "obj": skin if skin is not None else c["obj"]} for c, skin in zip(cases, skins)]

    reference = hugger.plan_many(mixed(), threads=1)
    done = []
    for _ in range(3):
        out = hugger.plan_many(mixed(), threads=threads, progress=lambda d, t: done.append(d))
        assert all(same(t, r) for t, r in zip(out, reference))
    assert done == list(range(1, 7)) * 3
    # the stream matters: the fourth case planned first, on a fresh skin, reads other noise
    assert not same(reference[3], hugger.plan_many([mixed()[3]], threads=1)[0])


def test_sensor_models_wrapping_one_noisy_skin_plan_as_in_one_thread(cases):
    # Each wrapper is a skin of its own, but all read the one noise stream they wrap.
    def wrapped():
        noisy = hugger.skins.SensorModel(cases[0]["obj"], gap_noise=2e-5, seed=1)
        return [{**c, "obj": hugger.skins.SensorModel(noisy, range=0.01 + 0.001 * i), "contact_tolerance": 4e-4}
                for i, c in enumerate(cases[:4])]

    reference = hugger.plan_many(wrapped(), threads=1)
    for _ in range(2):
        assert all(same(t, r) for t, r in zip(hugger.plan_many(wrapped(), threads=4), reference))


def test_cases_are_grouped_by_the_stateful_skins_they_wrap(cases):
    from hugger import batch

    noisy = hugger.skins.SensorModel(cases[0]["obj"], gap_noise=2e-6)
    model = hugger.skins.SensorModel(noisy, range=0.1)  # a model of it: reads its stream
    mesh = hugger.skins.MeshSkin(cases[1]["obj"])
    skins = [model, hugger.skins.SensorModel(mesh), noisy, hugger.skins.SensorModel(mesh),
             hugger.skins.SensorModel(model, taxel_spacing=0.004), cases[5]["obj"]]
    jobs = [batch._job(i, {**c, "obj": skin}, None, {}, None) for i, (c, skin) in enumerate(zip(cases, skins))]
    # 0, 2 and 4 read noisy's stream; 1 and 3 each their own model over a stateless skin
    assert batch._groups(jobs) == [[0, 2, 4], [1], [3], [5]]


def test_plans_pass_the_checker(cases, checker, tmp_path):
    for i, t in enumerate(hugger.plan_many(cases[:2], threads=2)):
        helpers.save_and_check(checker, t, tmp_path / f"plan{i}.npz", samples=30)


def test_case_forms_and_shared_hand(cases, sequential, hand):
    c0, c1, c2 = cases[0], cases[1], cases[2]

    @dataclass(frozen=True)
    class Case:  # like hugger.scenarios.Case: no hand of its own
        obj: hugger.Object
        target: np.ndarray
        palm_pose: np.ndarray

    forms = [
        (hand, c0["obj"], c0["target"], c0["palm_pose"]),
        {"obj": c1["obj"], "target": c1["target"], "palm_pose": c1["palm_pose"]},
        Case(c2["obj"], np.zeros(3), c2["palm_pose"]),
    ]
    out = hugger.plan_many(forms, hand=hand, threads=2)
    for t, ref in zip(out, sequential[:3]):
        assert same(t, ref)


def test_a_case_without_a_hand_takes_plan_many_s_hand(hand):
    with_hand = hugger.scenarios.default_case("sphere", hand)
    without = replace(with_hand, hand=None)
    a, b = hugger.plan_many([with_hand, without], hand=hand, threads=1)
    assert same(a, b)


def test_a_mapping_case_names_the_object_obj_only(cases, hand):
    c = cases[0]
    with pytest.raises(ValueError, match=r"case 0: unknown keys \['object'\] \(the object's key is 'obj'\)"):
        hugger.plan_many([{"object": c["obj"], "target": c["target"], "palm_pose": c["palm_pose"]}], hand=hand)


def test_default_cases_carry_their_hand_and_share_loaded_objects():
    small = hugger.Hand(fingers=3, links=3)
    cases = [hugger.scenarios.default_case("sphere", small), hugger.scenarios.default_case("sphere")]
    assert cases[0].hand is small and isinstance(cases[1].hand, hugger.Hand)
    assert cases[0].obj is cases[1].obj  # made once
    a, b = hugger.plan_many(cases, threads=2)  # no hand argument needed
    assert a.hand["fingers"] == 3 and b.hand["fingers"] == 5


def test_parameters_global_and_per_case(cases, hand):
    c = cases[0]
    a, b = hugger.plan_many([(hand, c["obj"], c["target"], c["palm_pose"], {"step": 5e-4}),
                             dict(c)], threads=2, step=8e-4)
    assert a.params["step"] == 5e-4 and b.params["step"] == 8e-4
    ref = hugger.plan(hand, c["obj"], c["target"], c["palm_pose"], step=5e-4)
    assert same(a, ref)


def test_progress_reports_every_case_in_the_calling_thread(cases):
    seen = []
    caller = threading.get_ident()

    def progress(done, total):
        seen.append((done, total, threading.get_ident()))

    hugger.plan_many(cases, threads=2, progress=progress)
    assert [(d, t) for d, t, _ in seen] == [(k, len(cases)) for k in range(1, len(cases) + 1)]
    assert all(ident == caller for _, _, ident in seen)


def test_a_failing_case_is_reported_with_its_index(cases, sequential, hand):
    # a well-formed case the planner refuses: the hand starts inside the object
    bad = dict(cases[1], palm_pose=hugger.look_at(np.add(cases[1]["target"], [0, 0, 0.01]), cases[1]["target"]))
    batch = [cases[0], bad, cases[2]]
    with pytest.raises(hugger.PlanManyError, match=r"1 of 3 cases failed:\n  case 1: ValueError: .*at the start") as info:
        hugger.plan_many(batch, threads=2)
    err = info.value
    assert set(err.errors) == {1} and isinstance(err.errors[1], ValueError)
    assert isinstance(err.__cause__, ValueError)
    assert err.results[1] is None and same(err.results[0], sequential[0]) and same(err.results[2], sequential[2])
    out = hugger.plan_many(batch, threads=2, errors="return")
    assert isinstance(out[1], hugger.CaseError) and out[1].index == 1 and isinstance(out[1].exception, ValueError)
    assert "case 1: ValueError" in str(out[1])
    assert same(out[0], sequential[0]) and same(out[2], sequential[2])
    # sequential mode reports the same way
    with pytest.raises(hugger.PlanManyError, match="case 1"):
        hugger.plan_many(batch, threads=1)


def test_timeout_applies_to_each_case(cases):
    slow = dict(cases[0], step=5e-5, contact_tolerance=1e-5, max_iterations=100000)
    out = hugger.plan_many([slow, cases[1]], threads=2, timeout=1e-3)
    assert out[0].status == "timeout"
    out = hugger.plan_many([dict(slow, timeout=1e-3), cases[1]], threads=2)
    assert out[0].status == "timeout" and out[1].status == "done"


def test_progress_exception_propagates(cases):
    def progress(done, total):
        raise KeyError("stop")

    with pytest.raises(KeyError, match="stop"):
        hugger.plan_many(cases, threads=2, progress=progress)


@pytest.mark.parametrize("kwargs, match", [
    ({"threads": 0}, "threads"),
    ({"threads": 1.5}, "threads"),
    ({"threads": True}, "threads"),
    ({"errors": "ignore"}, "errors"),
    ({"progress": 3}, "progress"),
    ({"timeout": -1.0}, "timeout"),
    ({"timeout": float("nan")}, "timeout"),
    ({"stepp": 1e-3}, "unknown planner parameters"),
    ({"hand": "hand"}, "hand"),
    ({"step": -1.0}, "step must be a positive finite number"),  # as Planner says, before any plan
    ({"rules": "x"}, "rules must be one of"),
    ({"skin": "x"}, "skin must be one of"),
    ({"max_iterations": 10**12}, "max_iterations must be between"),
])
def test_bad_arguments(cases, kwargs, match):
    with pytest.raises(ValueError, match=match):
        hugger.plan_many(cases[:1], **kwargs)


@pytest.mark.parametrize("case, match", [
    ({"obj": None, "target": [0, 0, 0], "palm_pose": np.eye(4)}, "case 0: obj, target and palm_pose"),
    ({"hand": None, "target": [0, 0, 0]}, "case 0: no hand"),
    ({"wat": 1}, "case 0: unknown keys"),
    ((1, 2, 3), "case 0: a tuple case"),
    (42, "case 0: expected a mapping"),
    ({"target": [0, 0, 0], "palm_pose": np.eye(3), "obj": hugger.objects.sphere(0.04)},
     r"case 0: palm_pose must have shape \(4, 4\)"),
    ({"target": [0, 0, 0], "palm_pose": np.eye(4), "obj": "o", "epsilon": -1}, "case 0: epsilon must be a positive"),
    ((None, None, None, None, 5), "case 0: a tuple case's fifth item must be a mapping of planner parameters, got int"),
])
def test_malformed_cases_are_refused_before_planning(hand, case, match):
    with pytest.raises(ValueError, match=match):
        hugger.plan_many([case], threads=2, hand=hand)


@pytest.mark.parametrize("edit, match", [
    # these were planned, and failed after the good cases (a PlanManyError, not a ValueError)
    ({"target": [0, 0]}, r"case 1: target must have shape \(3\)"),
    ({"target": [np.nan, 0, 0]}, "case 1: target must be a finite 3-vector"),
    ({"target": "abc"}, "case 1: target must be an array of real numbers"),
    ({"target": [1.0, 1.0, 1.0]}, "case 1: target T = .* is not inside the object"),
    ({"obj": "sphere"}, "case 1: obj must be a hugger.Object or a hugger.skins.Sensing skin, got str"),
    ({"hand": "5x5"}, "case 1: hand must be a hugger.Hand, got str"),
])
def test_every_malformed_case_is_refused_before_any_is_planned(cases, edit, match):
    planned: list[int] = []
    with pytest.raises(ValueError, match=match):
        hugger.plan_many([cases[0], dict(cases[1], **edit)], threads=1, errors="return",
                         progress=lambda done, total: planned.append(done))
    assert planned == []


def test_empty_and_not_iterable():
    assert hugger.plan_many([], threads=2) == []
    with pytest.raises(ValueError, match="iterable"):
        hugger.plan_many(5)


def test_cases_sharing_a_stateless_skin_run_in_parallel(cases, monkeypatch):
    # grouped are only the cases whose shared skin keeps state: a mesh skin's are not
    from hugger import batch

    mesh = hugger.skins.MeshSkin(cases[0]["obj"])
    noisy = hugger.skins.SensorModel(cases[0]["obj"], gap_noise=2e-6)
    jobs = [batch._job(i, {**c, "obj": skin}, None, {}, None)
            for i, (c, skin) in enumerate(zip(cases, [mesh, mesh, noisy, mesh, noisy, cases[5]["obj"]]))]
    assert batch._groups(jobs) == [[0], [1], [2, 4], [3], [5]]
