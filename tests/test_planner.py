"""The planner: step/plan, parameters, refusals of bad targets and starts, timeouts, determinism, threads."""
from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import helpers
import hugger
from helpers import BAD_POSES, no_warnings, start

HERE = Path(__file__).resolve()


# --- planner ------------------------------------------------------------------------------

def test_stream_equals_plan(hand, fine_sphere, fine_sphere_plan):
    streamed = list(hugger.Planner(hand, fine_sphere, [0, 0, 0], start()))
    traj = fine_sphere_plan
    assert len(streamed) == len(traj)
    for k in (0, len(traj) // 2, len(traj) - 1):
        np.testing.assert_array_equal(streamed[k].joints, traj.joints[k])
        np.testing.assert_array_equal(streamed[k].palm_pose, traj.palm_pose[k])
        assert streamed[k].iteration == k
    assert streamed[0].phase == 0 and streamed[-1].phase == 2


def test_step_then_plan_continues(hand, fine_sphere):
    turned = hugger.scenarios.start_pose(fine_sphere, hand, [0, 0, 0], turn_deg=60)  # Phase 1 has work to do
    planner = hugger.Planner(hand, fine_sphere, [0, 0, 0], turned)
    first = [planner.step() for _ in range(10)]
    assert planner.status == "running"
    partial = planner.trajectory()  # exactly what step() handed out, although Phase 1 is precomputed
    assert len(partial) == 10
    np.testing.assert_array_equal(partial.joints[-1], first[-1].joints)
    traj = planner.plan()
    assert traj.status == "done" and planner.step() is None
    np.testing.assert_array_equal(traj.joints[9], first[9].joints)


def test_defaults_are_resolved(hand, fine_sphere):
    p = hugger.Planner(hand, fine_sphere, [0, 0, 0], start()).params
    assert p["step"] == pytest.approx(0.001) and p["epsilon"] == pytest.approx(0.0001)
    assert p["contact_tolerance"] == 1e-4 and p["max_iterations"] == 20000


def test_max_iterations_gives_a_valid_partial_plan(hand, fine_sphere):
    traj = hugger.Planner(hand, fine_sphere, [0, 0, 0], start(), max_iterations=5).plan()
    # the approach before the first contact is one iteration of several configurations
    assert traj.status == "max_iterations" and traj.stats["phase2_iterations"] == 5
    assert np.sum(traj.phase == 2) >= traj.stats["approach_configurations"] >= 5


@pytest.mark.parametrize("target, pose, match", [
    ([0.1, 0, 0], None, "not inside"),
    ("vertex", None, "not inside"),  # exactly at a vertex: on the surface, not inside
    ([0, 0, float("nan")], None, "target"),
    ([0, 0], None, "target"),
    ([0, 0, 0], start(0.03), "inside|penetrates|touches"),
    ([0, 0, 0], start(0.1), "touches|penetrates"),
    ([0, 0, 0], np.diag([1.0, 1.0, 2.0, 1.0]), "rigid"),
    ([0, 0, 0], np.eye(3), r"\(4, 4\)"),
])
def test_planner_rejects_bad_starts(hand, fine_sphere, target, pose, match):
    if isinstance(target, str):
        target = fine_sphere.vertices[7]
    with pytest.raises(ValueError, match=match):
        hugger.Planner(hand, fine_sphere, target, start() if pose is None else pose)


@pytest.mark.parametrize("kwargs, match", [
    ({"step": 0}, "step"), ({"step": -0.001}, "step"), ({"step": 0.05}, "step"), ({"step": float("inf")}, "step"),
    ({"epsilon": 0}, "epsilon"), ({"epsilon": 0.01}, "epsilon"),
    ({"contact_tolerance": -1}, "contact_tolerance"), ({"contact_tolerance": 0.01}, "contact_tolerance"),
    ({"max_iterations": 0}, "max_iterations"), ({"max_iterations": 2.5}, "max_iterations"),
    ({"step": -1e-3}, "step"), ({"step": float("nan")}, "step"), ({"step": 0.0201}, "shortest link"),
    ({"step": 1e-300}, "contact_tolerance .* smaller than step"),
    ({"epsilon": -0.001}, "epsilon"), ({"epsilon": float("nan")}, "epsilon"), ({"epsilon": float("inf")}, "epsilon"),
    ({"epsilon": 0.0011}, "epsilon .* must not exceed step"),
    ({"contact_tolerance": 0}, "contact_tolerance"), ({"contact_tolerance": float("nan")}, "contact_tolerance"),
    ({"max_iterations": -5}, "max_iterations"), ({"max_iterations": True}, "max_iterations"),
    ({"max_iterations": "10"}, "max_iterations"),
])
def test_planner_rejects_bad_parameters(hand, sphere, kwargs, match):
    with pytest.raises(ValueError, match=match):
        hugger.Planner(hand, sphere, [0, 0, 0], start(), **kwargs)


def test_a_short_hand_s_defaults_are_named_where_they_meet(sphere):
    # links of 2 mm: the default step (0.1 mm) reaches the default contact tolerance
    tiny = hugger.Hand(fingers=3, links=3, link_length=0.002, link_radius=0.0005, palm_radius=0.004)
    with pytest.raises(ValueError, match=r"\(defaults: step the shortest link / 20, contact_tolerance 1e-4 m; give a "
                                         r"smaller contact_tolerance for links this short\)"):
        hugger.Planner(tiny, sphere, [0, 0, 0], start())
    for given in ({"step": 1e-4, "contact_tolerance": 1e-4}, {"contact_tolerance": 1e-4}, {"step": 1e-4}):
        with pytest.raises(ValueError, match=r"smaller than step \(0.0001 m\)$"):  # not both defaulted
            hugger.Planner(tiny, sphere, [0, 0, 0], start(), **given)


def test_sideways_start_that_would_sweep_through_the_object_is_refused(hand, fine_sphere):
    pose = np.eye(4)
    pose[:3, 3] = [0.075, 0, 0]
    with pytest.raises(ValueError, match="Phase 1"):
        hugger.Planner(hand, fine_sphere, [0, 0, 0], pose)


# --- the reference grasp: the 5x5 hand on a 4 cm sphere with T at its centre -------------------

def test_sphere_hug_has_palm_and_most_links_in_contact(tmp_path):
    hand = hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03,
                       palm_thickness=0.01)
    obj = hugger.objects.sphere(radius=0.04, subdivisions=5)
    rot = np.array([[np.cos(0.8), 0, np.sin(0.8)], [0, 1, 0], [-np.sin(0.8), 0, np.cos(0.8)]])
    start = hugger.look_at([0.0, 0.0, 0.2], [0, 0, 0])
    start[:3, :3] = rot @ start[:3, :3]  # turned away from T, so Phase 1 has work to do
    planner = hugger.Planner(hand, obj, [0, 0, 0], start)
    traj = planner.plan()
    s = traj.summary(contact_distance=1e-3)
    assert traj.status == "done"
    assert s["phase1_configurations"] > 0
    assert s["palm_contact"], s
    assert s["links_in_contact"] >= 15, s
    # no link penetrates: every final gap is non-negative
    assert traj.link_gaps().min() >= 0.0


# --- palm poses that are not rigid -------------------------------------------------------------

@pytest.mark.parametrize("pose, match", BAD_POSES)
def test_planner_refuses_non_rigid_palm_poses(hand, sphere, pose, match):
    with pytest.raises(ValueError, match=match):
        hugger.Planner(hand, sphere, [0, 0, 0], pose)


def test_nearly_rigid_pose_is_accepted_and_made_exactly_rigid(hand, sphere):
    pose = start()
    pose[:3, :3] += 1e-9 * np.arange(9).reshape(3, 3)  # within the 1e-6 tolerance
    traj = hugger.Planner(hand, sphere, [0, 0, 0], pose, max_iterations=3).plan()
    r = traj.palm_pose[:, :3, :3]
    assert np.abs(np.einsum("kji,kjl->kil", r, r) - np.eye(3)).max() < 1e-14
    np.testing.assert_allclose(hand.forward(pose, np.zeros((5, 5))), traj.joints[0], atol=1e-8)


# --- the target T -----------------------------------------------------------------------------

@pytest.mark.parametrize("where", ["face centroid", "edge midpoint", "far away", "below the object"])
def test_target_not_strictly_inside_is_refused(hand, sphere, where):
    v, f = sphere.vertices, sphere.faces
    target = {"face centroid": v[f[10]].mean(axis=0), "edge midpoint": v[f[10, :2]].mean(axis=0),
              "far away": [1e5, 0, 0], "below the object": [0, 0, -0.05]}[where]
    with pytest.raises(ValueError, match="not inside"):
        hugger.Planner(hand, sphere, target, start())


def _plan_off_target(rules, centre):
    """A plan whose skin has its object away from T (see the test below): (status, final tip
    states, the least distance T lies ahead of the palm's front plane, that distance at the end,
    configurations, the steps of the palm, first_contact_iteration)."""
    hand = hugger.Hand()
    target = np.zeros(3)
    planner = hugger.Planner(hand, hugger.skins.SphereSkin(0.04, centre), target, hugger.look_at([0, 0.2, 0], target),
                             rules=rules, max_iterations=200)
    traj = planner.plan()
    origin, p = traj.palm_pose[:, :3, 3], traj.palm_pose[:, :3, 2]
    ahead = ((target - origin) * p).sum(axis=1)
    return (traj.status, traj.tip_state[-1].tolist(), float(ahead.min()), float(ahead[-1]), len(traj),
            planner.params["step"], traj.stats["first_contact_iteration"])


CENTRES = [(0.3, 0.0, 0.0), (0.0, -0.3, 0.0), (0.05, 0.0, -0.3)]


@pytest.mark.parametrize("rules", ["paper", "hug"])
def test_a_skin_whose_object_is_not_at_the_target_stops_the_palm_at_the_target(rules):
    # A skin cannot be asked whether T lies inside its object (a displaced object in simulation,
    # a user's skin): nothing is ever touched here. The palm stops with its front plane at T and
    # the fingers close (the hand is blocked): the plan ends in a few hundred configurations.
    # Before the palm was bounded by T, each approach iteration advanced by the growing gap (the
    # plan grew without bound inside one iteration): in a subprocess, so that such a regression
    # fails by the timeout instead of taking the machine's memory.
    code = ("import json, sys; sys.path.insert(0, sys.argv[1]); import test_planner as t; "
            f"print(json.dumps([t._plan_off_target({rules!r}, c) for c in t.CENTRES]))")
    out = subprocess.run([sys.executable, "-c", code, str(HERE.parent)], capture_output=True, text=True, timeout=120,
                         check=True)
    for status, states, least, last, n, step, first_contact in json.loads(out.stdout):
        assert status == "done" and states == [2] * 5  # every finger DONE
        assert least >= -1e-12 and abs(last) <= 1e-12  # the palm reaches T and never passes it
        assert n < 0.2 / step + 200
        assert first_contact == -1  # nothing was felt (the fingers were released at T, not touched)


def test_target_just_inside_a_vertex_is_accepted(hand, sphere):
    target = sphere.vertices[7] * (1 - 1e-6)
    assert hugger.Planner(hand, sphere, target, start(), max_iterations=2).plan().status == "max_iterations"


def test_target_at_the_palm_origin_is_refused(hand):
    big = hugger.objects.sphere(radius=0.5, subdivisions=2)
    with pytest.raises(ValueError, match="target|touches|penetrates"):
        hugger.Planner(hand, big, [0, 0, 0.1], hugger.look_at([0, 0, 0.1], [0, 0, 1]))


# --- the start: inside, touching, too close for Phase 1 ---------------------------------------

def _gap(hand, obj, height):
    """Gap (m) between the extended fingers' capsules and obj, palm facing down from ``height``."""
    j = hand.forward(start(height), np.zeros((hand.fingers, hand.links)))
    return float(obj.segment_distance(j[:, :-1].reshape(-1, 3), j[:, 1:].reshape(-1, 3)).min() - hand.link_radius)


def _touching_height(hand, obj):
    """Palm height at which the extended fingers just touch obj (gap 0, by bisection on the mesh)."""
    lo, hi = 0.05, 0.3
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _gap(hand, obj, mid) > 0 else (mid, hi)
    return hi


def _facing_away(height):
    pose = np.eye(4)
    pose[:3, 3] = [0, 0, height]  # palm normal +z, away from the sphere below
    return pose


@pytest.mark.parametrize("pose, match", [
    (np.eye(4), "coincides|inside|penetrates"),      # P_o at T, inside O
    (start(0.04), "touches|penetrates"),             # the palm's face on the sphere
    (start(0.0605), "touches|penetrates"),           # fingers deep in it, palm clear
    ("touching", "touches"),                         # fingertips exactly on it (gap 0)
    ("within tolerance", "touches"),                 # a gap below contact_tolerance counts as touching
    (_facing_away(0.1), "Phase 1"),                  # turning 180 degrees sweeps the fingers through it
    (hugger.look_at([0.0, 0.09, 0.09], [0, 0, 0.5]), "Phase 1"),
])
def test_start_inside_touching_or_too_close_is_refused(hand, sphere, pose, match):
    if isinstance(pose, str):
        h = _touching_height(hand, sphere) + (0.0 if pose == "touching" else 5e-5)
        assert _gap(hand, sphere, h) < 1e-4  # contact_tolerance
        pose = start(h)
    with pytest.raises(ValueError, match=match):
        hugger.Planner(hand, sphere, [0, 0, 0], pose)


def test_start_clear_by_a_millimetre_is_accepted(hand, sphere):
    h = _touching_height(hand, sphere) + 0.001
    assert 0.0005 < _gap(hand, sphere, h) < 0.001
    traj = hugger.Planner(hand, sphere, [0, 0, 0], start(h)).plan()
    assert traj.status == "done" and traj.stats["first_contact_iteration"] >= 1


# --- planner parameters -------------------------------------------------------------------------

def test_the_engine_gives_typed_results(hand, sphere):
    """The compiled planner gives PlannerParams, PlannerStats, Configuration and History objects; the
    Python planner's params and stats stay dicts (as a trajectory records them)."""
    core = hugger._core
    assert core.PlannerParams().step is None  # None: the default, resolved by the planner
    p = hugger.Planner(hand, sphere, [0, 0, 0], start(), max_iterations=3, rules="paper")
    params = p._core.params
    assert isinstance(params, core.PlannerParams) and params.step == pytest.approx(0.001)
    assert (params.max_iterations, params.rules) == (3, "paper")
    assert p.params == {"step": params.step, "epsilon": params.epsilon, "contact_tolerance": params.contact_tolerance,
                        "max_iterations": 3, "rules": "paper", "skin": "section"}
    c = p._core.configuration(0)
    assert isinstance(c, core.Configuration) and (c.phase, c.iteration) == (0, 0)
    assert c.joints.shape == (5, 6, 3) and c.angles.shape == (5, 5) and c.tip_state.dtype == np.int8
    traj = p.plan()
    stats = p._core.stats
    assert isinstance(stats, core.PlannerStats) and p.stats["phase2_iterations"] == stats.phase2_iterations == 3
    h = p._core.history(1, 3)
    assert isinstance(h, core.History) and h.palm_pose.shape == (2, 4, 4)
    np.testing.assert_array_equal(h.joints, traj.joints[1:3])


def test_a_trajectory_records_the_stats_and_params_as_json_dumps_writes_them(hand, sphere):
    """The engine writes the counters' JSON itself (stats_json) and the parameters' JSON is made
    when the planner is made: both are json.dumps of the dicts Planner.stats and Planner.params
    give, character for character, before, during and after a plan (-1 counters included)."""
    import json

    p = hugger.Planner(hand, sphere, [0, 0, 0], start(), step=0.0015)
    seen = set()
    while True:
        assert p._core.stats_json == json.dumps(p.stats)
        assert p.trajectory().stats_json == json.dumps(p.stats)
        assert p.trajectory().params_json == json.dumps(p.params)
        seen.add(p.stats["first_contact_iteration"])
        if p.step() is None:
            break
    assert -1 in seen and len(seen) > 1  # before and after the first touch
    assert json.loads(p.trajectory().stats_json) == p.stats and p.stats["phase2_iterations"] > 0


def test_step_equal_to_a_link_is_allowed_and_ends(hand, sphere):
    traj = hugger.Planner(hand, sphere, [0, 0, 0], start(), step=0.02, epsilon=0.002).plan()
    assert traj.status == "done"


def test_absurd_max_iterations_gets_a_value_error(hand, sphere):
    with pytest.raises(ValueError, match="max_iterations"):
        hugger.Planner(hand, sphere, [0, 0, 0], start(), max_iterations=10 ** 30)


def test_contact_tolerance_below_double_resolution_is_refused(hand, sphere):
    try:
        traj = hugger.Planner(hand, sphere, [0, 0, 0], start(), contact_tolerance=1e-18, max_iterations=400).plan()
    except ValueError as exc:
        assert "contact_tolerance" in str(exc)
        return
    assert traj.status == "done", f"ran to {traj.status} with first contact {traj.stats['first_contact_iteration']}"


def test_a_skin_scene_far_from_the_origin_is_refused(hand):
    # A skin records no mesh: T and the start must lie where an object's coordinates may (the
    # files loaded back hold them), and the contact tolerance in force, given or the default,
    # must be above the resolution there.
    for c in (1e15, 2e6):
        c = np.array([c, 0.0, 0.0])
        with pytest.raises(ValueError, match="palm_pose's translation lies beyond 1e\\+06 m"):
            hugger.Planner(hand, hugger.skins.SphereSkin(0.04, c), c, hugger.look_at(c + [0, 0, 0.2], c))
        with pytest.raises(ValueError, match="target lies beyond 1e\\+06 m"):
            hugger.Planner(hand, hugger.skins.SphereSkin(0.04), c, start())
    c = np.array([5e5, 0.0, 0.0])
    pose = hugger.look_at(c + [0, 0, 0.2], c)
    with pytest.raises(ValueError, match="below the resolution"):
        hugger.Planner(hand, hugger.skins.SphereSkin(0.04, c), c, pose, contact_tolerance=1e-5)
    far_start = hugger.look_at([0, 0, 1.5e6], [0, 0, 0])
    with pytest.raises(ValueError, match="palm_pose's translation lies beyond"):
        hugger.Planner(hand, hugger.skins.SphereSkin(0.04), [0, 0, 0], far_start)
    hugger.Planner(hand, hugger.skins.SphereSkin(0.04, c), c, pose)  # the default tolerance is enough there


@pytest.mark.parametrize("which", ["target", "palm_pose"])
def test_complex_target_or_pose_gets_a_value_error(hand, sphere, which):
    args = {"target": np.zeros(3), "palm_pose": start()}
    args[which] = args[which] + 1e-3j
    with pytest.raises(ValueError, match=which):
        hugger.Planner(hand, sphere, **args)


# --- objects far smaller than a link or far larger than the reach ------------------------------

@pytest.mark.parametrize("make, warns, palm", [
    (lambda: hugger.objects.sphere(radius=0.0004, subdivisions=2), True, True),    # 0.8 mm: a crumb
    (lambda: hugger.objects.sphere(radius=0.002, subdivisions=2), False, True),    # 4 mm, a fifth of a link
    (lambda: hugger.objects.sphere(radius=1.0, subdivisions=3), False, False),     # 2 m: a wall to this hand
    (lambda: hugger.objects.box((10.0, 10.0, 10.0), divisions=2), True, False),    # 10 m
])
def test_objects_far_from_the_hands_size_end_done(hand, request, tmp_path, make, warns, palm):
    if warns:
        with pytest.warns(UserWarning, match="implausibly"):
            obj = make()
    else:
        obj = no_warnings(make)
    top = float(obj.bounds[1, 2])
    traj = hugger.Planner(hand, obj, [0, 0, 0], start(top + 0.15)).plan()
    s = traj.summary()
    assert s["status"] == "done" and s["phase2_iterations"] < traj.params["max_iterations"] // 10
    # the planner's own count; an iteration that approaches free space emits several configurations
    assert s["phase2_iterations"] == traj.stats["phase2_iterations"] <= s["phase2_configurations"]
    assert s["phase2_configurations"] == int(np.sum(traj.phase == 2))
    assert s["fingers_done"] == 5 and s["palm_contact"] == palm
    checker = request.getfixturevalue("checker")  # skips here when ../shared is absent
    helpers.save_and_check(checker, traj, tmp_path / "plan.npz", every=10)


# --- timeouts: Planner.plan(timeout=...) and hugger.plan(..., timeout=...) --------------------

# Start clear of the sphere, turned away from T so that Phase 1 has work to do.
START = hugger.look_at([0.0, 0.0, 0.2], [0, 0, 0])


def slow_planner(hand, sphere):
    """A plan of thousands of iterations (a step 1/400 of a link): far longer than a millisecond."""
    return hugger.Planner(hand, sphere, [0, 0, 0], START, step=5e-5, contact_tolerance=1e-5, max_iterations=100000)


@pytest.mark.parametrize("bad", [0, 0.0, -1.0, float("nan"), float("inf"), -float("inf"), True, "1", [1.0]])
def test_bad_timeouts_are_refused(hand, sphere, bad):
    p = hugger.Planner(hand, sphere, [0, 0, 0], START)
    with pytest.raises(ValueError, match="timeout"):
        p.plan(timeout=bad)
    assert p.status == "running"  # nothing was planned
    with pytest.raises(ValueError, match="timeout"):
        hugger.plan(hand, sphere, [0, 0, 0], START, timeout=bad)


def test_core_refuses_bad_timeouts_too(hand, sphere):
    p = hugger.Planner(hand, sphere, [0, 0, 0], START)
    for bad in (0.0, -2.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="timeout"):
            p._core.plan(bad)


def test_generous_timeout_changes_nothing(hand, sphere, sphere_plan):
    a = sphere_plan  # planned without a timeout
    b = hugger.Planner(hand, sphere, [0, 0, 0], START).plan(timeout=600)
    c = hugger.plan(hand, sphere, [0, 0, 0], START, timeout=600.0)
    assert a.status == b.status == c.status == "done"
    for t in (b, c):
        assert np.array_equal(a.joints, t.joints) and np.array_equal(a.palm_pose, t.palm_pose)
        assert np.array_equal(a.tip_state, t.tip_state)


def test_timeout_stops_with_a_valid_partial_trajectory(hand, sphere, checker, tmp_path):
    full = slow_planner(hand, sphere).plan()
    assert full.status == "done"
    planner = slow_planner(hand, sphere)
    part = planner.plan(timeout=1e-3)
    assert part.status == "timeout" == planner.status
    assert 1 <= len(part) < len(full)
    # the partial plan is the full plan's beginning, bit for bit (plans are deterministic)
    k = len(part)
    assert np.array_equal(part.joints, full.joints[:k]) and np.array_equal(part.palm_pose, full.palm_pose[:k])
    assert np.array_equal(part.tip_state, full.tip_state[:k])
    # a timed-out plan has ended: planning again or stepping adds nothing
    assert planner.plan().status == "timeout" and len(planner.trajectory()) == k
    assert planner.step() is None
    path = tmp_path / "partial.npz"
    helpers.save_and_check(checker, part, path, samples=40)
    assert hugger.Trajectory.load(path).status == "timeout"


@pytest.mark.parametrize("turn", [400.0, -181.0, float("nan"), float("inf"), "sixty"])
def test_a_start_turned_past_half_a_turn_is_refused(hand, sphere, turn):
    # start_pose and default_case (hugger plan --turn) share the rule: -180 to 180 degrees
    with pytest.raises(ValueError, match=r"turn_deg \(--turn\) must be"):
        hugger.scenarios.start_pose(sphere, hand, [0, 0, 0], turn_deg=turn)
    with pytest.raises(ValueError, match=r"turn_deg \(--turn\) must be"):
        hugger.scenarios.default_case("sphere", hand, turn_deg=turn)
    np.testing.assert_array_equal(hugger.scenarios.start_pose(sphere, hand, [0, 0, 0], turn_deg=180),
                                  hugger.scenarios.start_pose(sphere, hand, [0, 0, 0], turn_deg=180.0))


def test_hugger_plan_refuses_an_unknown_parameter_as_plan_many_does(hand, sphere):
    for call in (lambda: hugger.plan(hand, sphere, [0, 0, 0], START, stepp=1e-3),
                 lambda: hugger.plan_many([(hand, sphere, [0, 0, 0], START)], stepp=1e-3)):
        with pytest.raises(ValueError, match=r"unknown planner parameters \['stepp'\]; expected some of .*'step'"):
            call()


def test_an_interrupted_plan_goes_on_to_the_same_plan(hand, sphere):
    # interrupt() from another thread (as Ctrl-C) stops plan() between iterations, wherever it is,
    # with KeyboardInterrupt and the plan still running; later calls go on, to the same bits
    kw = dict(skin="mesh", step=2e-4, contact_tolerance=1e-4)
    whole = hugger.Planner(hand, sphere, [0, 0, 0], start(), **kw).plan()
    p = hugger.Planner(hand, sphere, [0, 0, 0], start(), **kw)
    sizes = []
    while True:
        timer = threading.Timer(0.01, p.interrupt)
        timer.start()
        try:
            p.plan()
            break
        except KeyboardInterrupt:
            assert p.status == "running"
            sizes.append(p._core.size)
            p.step()  # stepping in between changes nothing either
        finally:
            timer.cancel()
    assert len(set(sizes)) >= 2 and 1 < sizes[0] < len(whole)  # stopped mid-plan, at several places
    t = p.trajectory()
    assert t.status == whole.status and np.array_equal(t.joints, whole.joints)
    assert np.array_equal(t.palm_pose, whole.palm_pose) and np.array_equal(t.angles, whole.angles)


def test_ctrl_c_while_stepping_loses_no_configuration(hand, sphere):
    # SIGINT (Ctrl-C) lands while step() plans, many times: each KeyboardInterrupt caught, the
    # stepping goes on with the next configuration, none lost (Python raised the exception as
    # the engine's call returned, and the configuration it had made went with it: a jump). The
    # handler raises it only while step() is called (as Python's own handler would there), so
    # that no signal lands elsewhere in the test.
    import signal

    kw = dict(skin="mesh", step=2e-5, contact_tolerance=1e-5)
    whole = hugger.Planner(hand, sphere, [0, 0, 0], start(), **kw).plan()
    p = hugger.Planner(hand, sphere, [0, 0, 0], start(), **kw)
    stop, armed = threading.Event(), [False]

    def press():
        while not stop.wait(0.002):
            os.kill(os.getpid(), signal.SIGINT)

    def handler(signum, frame):
        if armed[0]:
            raise KeyboardInterrupt

    got, interrupts = [], 0
    previous = signal.signal(signal.SIGINT, handler)
    presser = threading.Thread(target=press)
    presser.start()
    try:
        while True:
            try:
                armed[0] = True
                c = p.step()
                armed[0] = False
            except KeyboardInterrupt:
                armed[0] = False
                interrupts += 1
                if interrupts >= 30:
                    stop.set()
                continue
            if c is None:
                break
            got.append(c)
    finally:
        armed[0] = False
        stop.set()
        presser.join()
        signal.signal(signal.SIGINT, previous)
    assert interrupts >= 30
    assert [c.iteration for c in got] == list(range(len(whole)))
    assert np.array_equal(np.stack([c.joints for c in got]), whole.joints)
    assert np.array_equal(p.trajectory().joints, whole.joints)


def step_cut_short(p: hugger.Planner) -> None:
    """One step() whose delivery is cut short: the engine makes the configuration, and a
    KeyboardInterrupt comes as its call returns (as Python raises a signal's exception there)."""
    real = p._core

    class CutShort:
        def __getattr__(self, name):
            return getattr(real, name)

        def configuration(self, k):
            real.configuration(k)
            raise KeyboardInterrupt

    p._core = CutShort()
    try:
        with pytest.raises(KeyboardInterrupt):
            p.step()
    finally:
        p._core = real


def test_stepping_after_an_interrupted_plan_loses_nothing_either(hand, sphere):
    # plan() interrupted, then step(): the configurations after plan()'s come one by one, and a
    # delivery cut short is handed out again there too
    kw = dict(skin="mesh", step=2e-4, contact_tolerance=1e-4)
    whole = hugger.Planner(hand, sphere, [0, 0, 0], start(), **kw).plan()
    p = hugger.Planner(hand, sphere, [0, 0, 0], start(), **kw)
    p.interrupt()  # the next plan() stops at once, after its first iteration at most
    with pytest.raises(KeyboardInterrupt):
        p.plan()
    done = p._core.size
    step_cut_short(p)
    rest = list(p)
    assert [c.iteration for c in rest] == list(range(done, len(whole)))
    assert np.array_equal(p.trajectory().joints, whole.joints)


def test_a_configuration_whose_delivery_was_cut_short_is_handed_out_next(hand, sphere):
    # the same, deterministic: the exception raised after the engine's call returned
    p = hugger.Planner(hand, sphere, [0, 0, 0], start(), skin="mesh")
    first = [p.step() for _ in range(3)]
    step_cut_short(p)
    rest = list(p)
    assert [c.iteration for c in first + rest] == list(range(len(p.trajectory())))


LONG_PLAN = """
import sys, time, hugger
from hugger.scenarios import default_case
c = default_case("curvy")
kw = dict(skin="mesh", step=4e-6, contact_tolerance=2e-6, max_iterations=1000000)
print("ready", flush=True)
try:
    if sys.argv[1] == "plan":
        hugger.Planner(c.hand, c.obj, c.target, c.palm_pose, **kw).plan()
    elif sys.argv[1] == "plan_many":
        hugger.plan_many([c] * 8, threads=2, **kw)
    else:
        hugger.search(c.hand, c.obj, c.target, approaches=8, threads=2, **kw)
    print("finished before the signal", flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
"""


@pytest.mark.parametrize("call", ["plan", "plan_many", "search"])
def test_ctrl_c_stops_a_long_plan_at_once(call):
    # The plans (about 10 s each here, GIL released, in the caller's thread or in two workers:
    # 8 plans of them) end within a fraction of a second of SIGINT, not when they are done.
    import signal

    p = subprocess.Popen([sys.executable, "-c", LONG_PLAN, call], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "ready"
        time.sleep(1.0)
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        out, _ = p.communicate(timeout=60)
        waited = time.monotonic() - sent
    finally:
        p.kill()
    assert out.strip() == "interrupted" and p.returncode == 0
    assert waited < 3.0, f"{call} ended {waited:.1f} s after SIGINT"


def test_timeout_through_hugger_plan(hand, sphere):
    t = hugger.plan(hand, sphere, [0, 0, 0], START, timeout=1e-3, step=5e-5, contact_tolerance=1e-5,
                    max_iterations=100000)
    assert t.status == "timeout"
    assert math.isclose(t.params["step"], 5e-5)


# --- determinism and threads ---------------------------------------------------------------

def _blob_plan(seed):
    obj = hugger.objects.blob(radius=0.035, seed=seed)
    hand = hugger.Hand(fingers=4, links=6, link_length=0.015, link_radius=0.002, palm_radius=0.025)
    return hugger.Planner(hand, obj, [0, 0, 0], hugger.look_at([0.02, 0.1, 0.15], [0, 0, 0])).plan()


def test_bit_identical_across_runs_and_threads():
    alone = [_blob_plan(s) for s in range(4)]
    again = [_blob_plan(s) for s in range(4)]
    results = [None] * 4

    def run(i):
        results[i] = _blob_plan(i)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b, c in zip(alone, again, results):
        assert a.joints.tobytes() == b.joints.tobytes() == c.joints.tobytes()
        assert a.palm_pose.tobytes() == c.palm_pose.tobytes()


def test_gil_is_released_while_planning():
    # A large mesh and the mesh skin (the slower reference): a plan of ~0.4 s, long enough to count
    # another thread's ticks during it (with the section skin it takes ~0.05 s).
    obj = hugger.objects.sphere(radius=0.04, subdivisions=6)
    hand = hugger.Hand(fingers=8, links=8, link_length=0.0125, link_radius=0.002)
    planner = hugger.Planner(hand, obj, [0, 0, 0], hugger.look_at([0, 0, 0.2], [0, 0, 0]), step=0.0003,
                             skin="mesh")
    elapsed, during = _ticks_while(planner.plan)
    # the other thread kept ticking during the plan (it could not if the GIL were held)
    assert elapsed > 0.05
    assert during > 0.2 * elapsed / 0.001


def test_one_planner_cannot_run_on_two_threads_at_once(hand, fine_sphere):
    planner = hugger.Planner(hand, hugger.objects.sphere(radius=0.04, subdivisions=6), [0, 0, 0], start(),
                             step=0.0002, skin="mesh")  # the slower reference skin: still planning 10 ms on
    errors = []
    t = threading.Thread(target=planner.plan)
    t.start()
    time.sleep(0.01)
    try:
        planner.step()
    except RuntimeError as exc:
        errors.append(str(exc))
    t.join()
    assert planner.status == "done"
    if errors:  # the first plan may already have finished on a fast machine
        assert "another thread" in errors[0]


# --- determinism and threads ----------------------------------------------------------------------

def _case():
    obj = hugger.objects.blob(radius=0.035, amplitude=0.3, seed=11, subdivisions=3)
    hand = hugger.Hand(fingers=4, links=6, link_length=0.015, link_radius=0.002, palm_radius=0.025)
    return hand, obj, hugger.look_at([0.05, -0.08, 0.14], [0, 0, 0])


def _fingerprint(traj: hugger.Trajectory) -> str:
    h = hashlib.sha256()
    for name in ("palm_pose", "joints", "angles", "tip_state", "phase"):
        h.update(np.ascontiguousarray(getattr(traj, name)).tobytes())
    h.update((traj.status + traj.params_json + traj.stats_json).encode())
    return h.hexdigest()


def test_shared_hand_and_object_on_two_threads_equal_the_plan_alone():
    hand, obj, pose = _case()
    alone = _fingerprint(hugger.Planner(hand, obj, [0, 0, 0], pose).plan())
    results: list = [None] * 4
    barrier = threading.Barrier(2)

    def run(i):
        barrier.wait()
        for j in (i, i + 2):
            if j < 2:
                results[j] = _fingerprint(hugger.Planner(hand, obj, [0, 0, 0], pose).plan())
            else:  # streamed one configuration at a time, interleaved with the other thread
                p = hugger.Planner(hand, obj, [0, 0, 0], pose)
                while p.step() is not None:
                    pass
                results[j] = _fingerprint(p.trajectory())

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results == [alone] * 4


def test_bit_identical_in_another_process():
    hand, obj, pose = _case()
    here = _fingerprint(hugger.Planner(hand, obj, [0, 0, 0], pose).plan())
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import test_planner as t; "
            "h, o, p = t._case(); import hugger; print(t._fingerprint(hugger.Planner(h, o, [0, 0, 0], p).plan()))")
    env = {**os.environ, "PYTHONHASHSEED": "12345"}
    out = subprocess.run([sys.executable, "-c", code, str(HERE.parent)], capture_output=True, text=True, env=env,
                         timeout=120, check=True)
    assert out.stdout.strip() == here


def _ticks_while(fn):
    """Run fn on this thread while another thread ticks every millisecond; (elapsed s, ticks during)."""
    ticks, done = [], threading.Event()

    def counter():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=counter)
    t.start()
    time.sleep(0.01)
    t0 = time.perf_counter()
    fn()
    t1 = time.perf_counter()
    done.set()
    t.join()
    return t1 - t0, sum(t0 <= x <= t1 for x in ticks)


def test_gil_is_released_during_phase_1_in_the_constructor(hand, sphere):
    pose = np.eye(4)
    pose[:3, 3] = [0, 0, 0.3]  # facing away: Phase 1 turns the hand through 180 degrees, ~75000 increments
    made = []
    elapsed, during = _ticks_while(lambda: made.append(hugger.Planner(hand, sphere, [0, 0, 0], pose, step=4e-6,
                                                                      contact_tolerance=2e-6)))
    assert made[0].stats["phase1_configurations"] > 50000
    assert elapsed > 0.05
    # the counter sleeps 1 ms a tick; with the GIL held it could not tick at all
    assert during > 0.2 * elapsed / 0.001


# --- bounded resources ------------------------------------------------------------------------

@pytest.mark.parametrize("distance, step, message", [
    (1000.0, None, "the approach would need more than 100000 steps"),
    (0.2, 1e-8, "the approach would need more than 100000 steps"),
    (1e16, None, "palm_pose's translation lies beyond 1e\\+06 m"),  # no scene's: refused as such
])
def test_an_approach_of_too_many_steps_is_refused_before_planning(hand, sphere, distance, step, message):
    # Each step of the approach is a configuration, all made in one iteration whatever the timeout:
    # a start that needs more than kMaxIncrements of them is refused (a timeout would not stop it).
    params = {} if step is None else {"step": step, "contact_tolerance": step / 2}
    with pytest.raises(ValueError, match=message):
        hugger.Planner(hand, sphere, [0, 0, 0], hugger.look_at([0, 0, distance], [0, 0, 0]), **params)


def test_an_approach_just_within_the_limit_plans(hand, sphere):
    # 0.15 m from T at a step of 1.6 um: 93,750 steps at most, accepted.
    p = hugger.Planner(hand, sphere, [0, 0, 0], hugger.look_at([0, 0, 0.15], [0, 0, 0]), step=1.6e-6,
                       contact_tolerance=8e-7, max_iterations=1)
    p.plan()
    assert 1 < len(p.trajectory()) <= 100001


def _rss_bytes() -> int:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="needs Linux /proc to read the resident memory")
def test_repeated_plans_do_not_leak_memory():
    import gc

    hand = hugger.Hand()
    obj = hugger.objects.sphere(0.04, subdivisions=5)  # 20480 triangles: a leaked tree would show
    pose = hugger.look_at([0, 0, 0.2], [0, 0, 0])
    for _ in range(3):  # warm up allocator pools
        hugger.plan(hand, hugger.Object(obj.vertices, obj.faces), [0, 0, 0], pose)
    gc.collect()
    before = _rss_bytes()
    for _ in range(25):
        traj = hugger.plan(hand, hugger.Object(obj.vertices, obj.faces), [0, 0, 0], pose)
        assert traj.status == "done"
    del traj
    gc.collect()
    grown = _rss_bytes() - before
    assert grown < 24 * 2**20, f"resident memory grew by {grown / 2**20:.1f} MiB over 25 plans"


def test_none_is_the_default_of_every_parameter(hand, sphere):
    # as plan_many and check_params take it: rules=None is "hug", as step=None is the default step
    pose = hugger.look_at([0, 0, 0.2], [0, 0, 0])
    ref = hugger.Planner(hand, sphere, [0, 0, 0], pose).plan()
    given = dict(step=None, epsilon=None, contact_tolerance=None, max_iterations=None, rules=None, skin=None)
    assert helpers.same(hugger.Planner(hand, sphere, [0, 0, 0], pose, **given).plan(), ref)
    assert helpers.same(hugger.plan_many([(hand, sphere, [0, 0, 0], pose)], threads=1, rules=None)[0], ref)


def test_look_at_refuses_a_non_finite_up():
    with pytest.raises(ValueError, match="up must be a finite 3-vector"):
        hugger.look_at([0, 0, 0.2], [0, 0, 0], up=[np.nan, 0, 0])
