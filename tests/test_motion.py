"""Plans a robot can execute (issue 16): the hard cases that used to fail, as regression tests.

Each plan is checked by the independent checker including its motion check: DONE fingers keep
their joint angles, no joint moves more than 4 s per Phase 2 iteration, and the swept motion
between configurations (palm interpolated, joint angles linearly) is collision-free. Both rule
sets, and no plan may end ``max_iterations``.
"""
from __future__ import annotations

import numpy as np
import pytest

import helpers
import hugger
from hugger import scenarios
from hugger.planner import look_at

RULES = ["paper", "hug"]


def checked(traj: hugger.Trajectory, checker, tmp_path, swept_every: int = 1) -> dict:
    """Save, run the checker with its motion check, assert it holds; the checker's figures."""
    figures = helpers.save_and_check(checker, traj, tmp_path / "plan.npz", motion=True, swept_every=swept_every)
    assert traj.status != "max_iterations"
    return figures


def comb(slot: float = 0.003, tooth: float = 0.003, teeth: int = 7, height: float = 0.012, base: float = 0.01,
         depth: float = 0.03) -> hugger.Object:
    """A comb: a bar of ``base`` along x with ``teeth`` teeth of width ``tooth`` and ``height``
    along +y, ``slot`` apart, extruded ``depth`` along z; centred at the origin."""
    width = teeth * tooth + (teeth - 1) * slot
    # the outline, counter-clockwise: the bar's bottom edge, then the teeth from right to left
    pts = [(0.0, 0.0), (width, 0.0)]
    top = []
    for k in range(teeth):  # right to left along the top
        x1 = width - k * (tooth + slot)
        x0 = x1 - tooth
        top += [(x1, base), (x1, base + height), (x0, base + height), (x0, base)]
    pts += top
    poly = np.array(pts)
    n = len(poly)
    v = np.concatenate([np.c_[poly, np.zeros(n)], np.c_[poly, np.full(n, depth)]])
    faces = []
    # caps: the bar [0, width] x [0, base] as a fan from (0, 0) over the points on y = base and
    # (width, 0); each tooth as two triangles
    on_base = [i for i in range(2, n) if poly[i, 1] == base]
    chain = [1] + on_base  # (width, 0), then the y = base points from right to left
    for a, b in zip(chain[:-1], chain[1:]):
        faces.append((0, b, a))
        faces.append((n, n + a, n + b))
    for k in range(teeth):
        i = 2 + 4 * k  # (x1, base), (x1, top), (x0, top), (x0, base)
        faces += [(i, i + 2, i + 1), (i, i + 3, i + 2)]
        faces += [(n + i, n + i + 1, n + i + 2), (n + i, n + i + 2, n + i + 3)]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i)]
    v = v - np.array([width / 2, (base + height) / 2, depth / 2])
    return hugger.Object(v, np.array(faces))


@pytest.mark.parametrize("rules", RULES)
def test_torus_finger_does_not_swing_through_the_tube(rules, checker, tmp_path):
    """Finger 2's last joint used to jump 144 degrees (the tip 38 steps) and pass through the tube."""
    T = np.array([0.06, 0.0, 0.0])
    hand = hugger.Hand(link_length=0.012, palm_radius=0.015)
    traj = hugger.Planner(hand, hugger.objects.torus(0.06, 0.01), T, look_at([-0.05, 0, -0.2], T), rules=rules).plan()
    figures = checked(traj, checker, tmp_path)
    assert figures["phase2_joint_step_max_over_step"] <= 4.0


@pytest.mark.parametrize("rules", RULES)
def test_done_fingers_are_not_dragged(rules, checker, tmp_path):
    """The palm beside a sphere: a DONE finger used to be dragged 9.7 cm while the palm slid past."""
    pose = np.eye(4)
    pose[:3, :3] = np.diag([1.0, -1.0, -1.0])
    pose[:3, 3] = [0.0399, 0.0, 0.1933]
    traj = hugger.Planner(hugger.Hand(), hugger.objects.sphere(0.04), [0.0399, 0, 0], pose, rules=rules).plan()
    figures = checked(traj, checker, tmp_path)
    assert figures["done_angle_change_max"] <= 1e-9


STALLS = [("torus", (0.0, 1.0, 0.0)), ("ycb_mug", (-1.0, 0.0, 0.0)), ("ycb_banana", (0.0, 1.0, 0.0))]


@pytest.mark.parametrize("rules", RULES)
@pytest.mark.parametrize("name,normal", STALLS, ids=[s[0] for s in STALLS])
def test_former_stalls_end_promptly(name, normal, rules, checker, tmp_path):
    """These used to burn max_iterations after ~19,800 identical iterations. ``normal`` is the
    palm normal as ``hugger plan --normal`` takes it (for the meshes: the direction of approach
    reversed, i.e. the hand comes from -normal)."""
    spec = name
    if name.startswith("ycb_"):
        path = helpers.OBJECTS_DIR / f"{name}.obj"
        if not path.is_file():
            pytest.skip(helpers.SHARED_MISSING)
        spec = str(path)
    hand = hugger.Hand()
    case = scenarios.default_case(spec, hand, normal=normal)
    planner = hugger.Planner(hand, case.obj, case.target, case.palm_pose, rules=rules)
    traj = planner.plan()
    checked(traj, checker, tmp_path, swept_every=1)
    assert traj.status in ("done", "stalled")
    assert planner.stats["phase2_iterations"] < 2000
    J, ts = traj.joints, traj.tip_state
    same = np.all(J[1:] == J[:-1], axis=(1, 2, 3)) & np.all(ts[1:] == ts[:-1], axis=1)
    assert not same[traj.phase[1:] == 2].any(), "a configuration repeats the one before"


#: Cases of the planner fuzz test (seed, shape, size) where a finger goes round a cycle: the first
#: with the 1 µm flattening of the section skin before e4ee900, the other three with its 10 µm
#: (with the cycle rule taken out, each ran to max_iterations with the hug rules and the section
#: skin, seed 86 with the mesh skin too; with it every plan here ends within 320 iterations). The
#: objects are turned by tests/helpers.py with NumPy's matrix product, which may round differently
#: on another processor (docs/objects.md): there a case may end without the cycle.
CYCLES = [(100, "cylinder", 0.01), (47, "cylinder", 0.03), (86, "cylinder", 0.03), (386, "box", 0.01)]


@pytest.mark.parametrize("skin", ["section", "mesh"])
@pytest.mark.parametrize("rules", RULES)
@pytest.mark.parametrize("seed,kind,size", CYCLES, ids=[f"{k}{s * 100:g}cm-{n}" for n, k, s in CYCLES])
def test_wide_oscillation_ends(seed, kind, size, rules, skin, checker, tmp_path):
    """Cases of the planner fuzz test (random hands on small objects, the palm landed) where, with
    the hug rules, one finger went round a cycle until max_iterations (seed 100 at the 1 µm
    flattening: 14 iterations a round, its tip 0.3 mm wide, wider than the overextension window's
    2 s, drifting by 0.4 nm a round). A finger that keeps coming back to within epsilon of a chain
    it had, the palm still, is at rest. The combinations that end without the rule (see CYCLES)
    are kept as plans of these hard cases."""
    rng = np.random.default_rng(seed)
    obj, _ = helpers.random_object(rng, kind, size)
    target = 0.4375 * obj.vertices[rng.integers(len(obj.vertices))]
    hand = helpers.random_hand(rng, size)
    pose = helpers.safe_start(rng, obj, hand, target)
    planner = hugger.Planner(hand, obj, target, pose, rules=rules, skin=skin, max_iterations=2000)
    traj = planner.plan()
    checked(traj, checker, tmp_path, swept_every=5)
    assert traj.status == "done"
    assert planner.stats["phase2_iterations"] < 500


@pytest.mark.parametrize("rules", RULES)
def test_far_start_approaches_by_the_free_distance(rules, checker, tmp_path):
    """A start 20 m away: the approach is one iteration of as many configurations (each palm
    step <= s) as the distance takes, not 20 m / s iterations against max_iterations."""
    hand = hugger.Hand()
    case = scenarios.default_case("sphere", hand)
    pose = case.palm_pose.copy()
    pose[:3, 3] -= 20.0 * pose[:3, 2]
    planner = hugger.Planner(hand, case.obj, case.target, pose, rules=rules, max_iterations=500)
    traj = planner.plan()
    assert traj.status == "done"
    stats = planner.stats
    assert stats["phase2_iterations"] < 500
    step = planner.params["step"]
    assert stats["approach_configurations"] >= 20.0 / step * 0.99
    checked(traj, checker, tmp_path, swept_every=50)


@pytest.mark.parametrize("rules", RULES)
def test_comb_with_thin_slots_zero_radius(rules, checker, tmp_path):
    """Link radius 0 on a comb with 3 mm slots: a tip used to jump 4.3 steps and cut a corner."""
    obj = comb()
    hand = hugger.Hand(fingers=4, links=5, link_length=0.01, link_radius=0.0, palm_radius=0.012)
    target = np.array([0.0, -0.008, 0.0])  # in the bar
    assert obj.inside(target)
    for direction in ([0.0, 1.0, 0.0], [0.3, 1.0, 0.2]):
        start = scenarios.start_pose(obj, hand, target, direction=direction)
        traj = hugger.Planner(hand, obj, target, start, rules=rules).plan()
        figures = checked(traj, checker, tmp_path)
        assert figures["phase2_joint_step_max_over_step"] <= 4.0


def test_streaming_matches_plan_with_several_configurations_per_iteration():
    """step() hands out the approach's configurations one by one, and stops at the end."""
    hand = hugger.Hand()
    case = scenarios.default_case("sphere", hand)
    a = hugger.Planner(hand, case.obj, case.target, case.palm_pose).plan()
    b = hugger.Planner(hand, case.obj, case.target, case.palm_pose)
    streamed = list(b)
    assert len(streamed) == len(a)
    assert np.array_equal(np.stack([c.joints for c in streamed]), a.joints)
    assert b.step() is None
