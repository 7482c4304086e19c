"""The Python API: construction, validation, streaming, files, threads."""
from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import hugger


@pytest.fixture(scope="module")
def sphere():
    return hugger.objects.sphere(radius=0.04, subdivisions=4)


def start(height=0.2):
    return hugger.look_at([0.0, 0.0, height], [0, 0, 0])


# --- hand ---------------------------------------------------------------------------------

def test_hand_properties_and_json(hand):
    assert hand.fingers == 5 and hand.links == 5
    assert hand.link_lengths.shape == (5, 5) and np.all(hand.link_lengths == 0.02)
    d = hand.to_dict()
    assert hugger.Hand.from_dict(d).to_dict() == d
    per_link = hugger.Hand(fingers=2, links=3, link_length=[[0.01, 0.02, 0.03], [0.03, 0.02, 0.01]], link_radius=0)
    assert per_link.link_lengths[1, 0] == 0.03


@pytest.mark.parametrize("kwargs, match", [
    ({"fingers": 0}, "fingers"),
    ({"fingers": 2.5}, "fingers"),
    ({"links": -1}, "links"),
    ({"link_length": 0.0}, "link_length"),
    ({"link_length": -0.02}, "link_length"),
    ({"link_length": np.ones((2, 2))}, "link_length"),
    ({"link_radius": -0.001}, "link_radius"),
    ({"link_radius": float("nan")}, "link_radius"),
    ({"palm_radius": 0}, "palm_radius"),
    ({"palm_thickness": -1}, "palm_thickness"),
    ({"palm_radius": "big"}, "palm_radius"),
])
def test_hand_rejects_bad_sizes(kwargs, match):
    with pytest.raises(ValueError, match=match):
        hugger.Hand(**kwargs)


def test_forward_and_inverse_kinematics(hand):
    rng = np.random.default_rng(0)
    pose = start()
    angles = rng.uniform(-1, 1, size=(5, 5))
    joints = hand.forward(pose, angles)
    assert joints.shape == (5, 6, 3)
    np.testing.assert_allclose(joints[:, 0], hand.roots(pose), atol=1e-15)
    np.testing.assert_allclose(hand.angles_from_joints(pose, joints), angles, atol=1e-12)


# --- object -------------------------------------------------------------------------------

def test_object_queries(sphere):
    assert sphere.inside([0, 0, 0]) and not sphere.inside([0.05, 0, 0])
    assert sphere.signed_distance([0.05, 0, 0]) == pytest.approx(0.01, abs=3e-4)
    assert sphere.volume == pytest.approx(4 / 3 * np.pi * 0.04 ** 3, rel=0.01)
    loops = sphere.section([0, 0, 0], [1, 0, 0], [0, 1, 0])
    assert len(loops) == 1 and np.linalg.norm(loops[0], axis=1) == pytest.approx(0.04, abs=3e-4)


def _mesh():
    return hugger.objects.icosphere(1)


@pytest.mark.parametrize("mutate, match", [
    (lambda v, f: (v[:0], f[:0]), "empty"),
    (lambda v, f: (np.where(np.arange(len(v))[:, None] == 3, np.nan, v), f), "not finite"),
    (lambda v, f: (np.where(np.arange(len(v))[:, None] == 3, np.inf, v), f), "not finite"),
    (lambda v, f: (v, np.where(f == f.max(), len(v) + 5, f)), "outside"),
    (lambda v, f: (v, np.vstack([f[:1] * 0 - 1, f[1:]])), "outside"),
    (lambda v, f: (v, f[:-1]), "not closed"),
    (lambda v, f: (v, np.vstack([f[:1, [0, 2, 1]], f[1:]])), "consistently oriented"),
    (lambda v, f: (v, f[:, [0, 2, 1]]), "inward"),
    (lambda v, f: (v, np.vstack([f, f[:1]])), "consistently oriented|manifold"),
    (lambda v, f: (v, np.vstack([[0, 0, 1], f])), "degenerate"),
    (lambda v, f: (v[:, :2], f), r"\(V, 3\)"),
    (lambda v, f: (v, f[:, :2]), r"\(F, 3\)"),
    (lambda v, f: (v, f + 0.5), "whole-number"),
])
def test_object_rejects_bad_meshes(mutate, match):
    v, f = _mesh()
    with pytest.raises(ValueError, match=match):
        hugger.Object(*mutate(v.copy(), f.copy()))


# --- planner ------------------------------------------------------------------------------

def test_stream_equals_plan(hand, sphere):
    streamed = list(hugger.Planner(hand, sphere, [0, 0, 0], start()))
    traj = hugger.Planner(hand, sphere, [0, 0, 0], start()).plan()
    assert len(streamed) == len(traj)
    for k in (0, len(traj) // 2, len(traj) - 1):
        np.testing.assert_array_equal(streamed[k].joints, traj.joints[k])
        np.testing.assert_array_equal(streamed[k].palm_pose, traj.palm_pose[k])
        assert streamed[k].iteration == k
    assert streamed[0].phase == 0 and streamed[-1].phase == 2


def test_step_then_plan_continues(hand, sphere):
    turned = hugger.scenarios.start_pose(sphere, hand, [0, 0, 0], turn_deg=60)  # Phase 1 has work to do
    planner = hugger.Planner(hand, sphere, [0, 0, 0], turned)
    first = [planner.step() for _ in range(10)]
    assert planner.status == "running"
    partial = planner.trajectory()  # exactly what step() handed out, although Phase 1 is precomputed
    assert len(partial) == 10
    np.testing.assert_array_equal(partial.joints[-1], first[-1].joints)
    traj = planner.plan()
    assert traj.status == "done" and planner.step() is None
    np.testing.assert_array_equal(traj.joints[9], first[9].joints)


def test_defaults_are_resolved(hand, sphere):
    p = hugger.Planner(hand, sphere, [0, 0, 0], start()).params
    assert p["step"] == pytest.approx(0.001) and p["epsilon"] == pytest.approx(0.0001)
    assert p["contact_tolerance"] == 1e-4 and p["max_iterations"] == 20000


def test_max_iterations_gives_a_valid_partial_plan(hand, sphere):
    traj = hugger.Planner(hand, sphere, [0, 0, 0], start(), max_iterations=5).plan()
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
def test_planner_rejects_bad_starts(hand, sphere, target, pose, match):
    if isinstance(target, str):
        target = sphere.vertices[7]
    with pytest.raises(ValueError, match=match):
        hugger.Planner(hand, sphere, target, start() if pose is None else pose)


@pytest.mark.parametrize("kwargs, match", [
    ({"step": 0}, "step"), ({"step": -0.001}, "step"), ({"step": 0.05}, "step"), ({"step": float("inf")}, "step"),
    ({"epsilon": 0}, "epsilon"), ({"epsilon": 0.01}, "epsilon"),
    ({"contact_tolerance": -1}, "contact_tolerance"), ({"contact_tolerance": 0.01}, "contact_tolerance"),
    ({"max_iterations": 0}, "max_iterations"), ({"max_iterations": 2.5}, "max_iterations"),
])
def test_planner_rejects_bad_parameters(hand, sphere, kwargs, match):
    with pytest.raises(ValueError, match=match):
        hugger.Planner(hand, sphere, [0, 0, 0], start(), **kwargs)


def test_sideways_start_that_would_sweep_through_the_object_is_refused(hand, sphere):
    pose = np.eye(4)
    pose[:3, 3] = [0.075, 0, 0]
    with pytest.raises(ValueError, match="Phase 1"):
        hugger.Planner(hand, sphere, [0, 0, 0], pose)


# --- trajectory file -----------------------------------------------------------------------

def test_save_load_round_trip(hand, sphere, tmp_path):
    traj = hugger.Planner(hand, sphere, [0, 0, 0], start()).plan()
    traj.save(tmp_path / "plan.npz")
    back = hugger.Trajectory.load(tmp_path / "plan.npz")
    for name in ("palm_pose", "joints", "angles", "tip_state", "phase", "object_vertices", "object_faces", "target"):
        np.testing.assert_array_equal(getattr(back, name), getattr(traj, name))
    assert back.status == "done" and back.hand == hand.to_dict() and back.params == traj.params
    with np.load(tmp_path / "plan.npz", allow_pickle=False) as z:
        assert int(z["format_version"]) == 1 and z["tip_state"].dtype == np.int8


def test_load_refuses_corrupt_and_pickled_files(tmp_path):
    (tmp_path / "junk.npz").write_bytes(b"not a zip file at all")
    with pytest.raises(ValueError, match="cannot read"):
        hugger.Trajectory.load(tmp_path / "junk.npz")
    np.savez(tmp_path / "pickled.npz", format_version=np.array([{"evil": 1}], dtype=object))
    with pytest.raises(ValueError):
        hugger.Trajectory.load(tmp_path / "pickled.npz")
    np.savez(tmp_path / "partial.npz", format_version=np.int64(1))
    with pytest.raises(ValueError, match="missing keys"):
        hugger.Trajectory.load(tmp_path / "partial.npz")


def test_truncated_file_is_refused(hand, sphere, tmp_path):
    traj = hugger.Planner(hand, sphere, [0, 0, 0], start(), max_iterations=20).plan()
    traj.save(tmp_path / "plan.npz")
    data = (tmp_path / "plan.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match="cannot read"):
        hugger.Trajectory.load(tmp_path / "cut.npz")


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
    obj = hugger.objects.sphere(radius=0.04, subdivisions=6)  # a large mesh: a plan of ~1 s
    hand = hugger.Hand(fingers=8, links=8, link_length=0.0125, link_radius=0.002)
    planner = hugger.Planner(hand, obj, [0, 0, 0], hugger.look_at([0, 0, 0.2], [0, 0, 0]), step=0.0003)
    ticks = []
    done = threading.Event()

    def counter():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=counter)
    t0 = time.perf_counter()
    t.start()
    planner.plan()
    elapsed = time.perf_counter() - t0
    done.set()
    t.join()
    # the other thread kept ticking during the plan (it could not if the GIL were held)
    during = [x for x in ticks if x < t0 + elapsed]
    assert elapsed > 0.05
    assert len(during) > 0.2 * elapsed / 0.001


def test_one_planner_cannot_run_on_two_threads_at_once(hand, sphere):
    planner = hugger.Planner(hand, hugger.objects.sphere(radius=0.04, subdivisions=6), [0, 0, 0], start(),
                             step=0.0002)
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
