"""Property tests over many random cases (docs/algorithm.md), each plan checked independently.

Objects: sphere, ellipsoid, box, cylinder, a smooth non-convex blob, and the meshes in
../shared/data/objects; random start poses at a safe distance with random palm orientations;
hands with M in 2..8, N in 2..8, link radius 0 and > 0. Both rule sets ("paper" and "hug");
every plan passes the independent checker including its motion check (DONE fingers keep their
angles, no joint moves more than 4 s per Phase 2 iteration, the swept motion is collision-free)
and none ends ``max_iterations``.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

import helpers
import hugger

KINDS = ["sphere", "ellipsoid", "box", "cylinder", "blob"]
SEEDS = range(200)


def random_case(seed: int):
    rng = np.random.default_rng(seed)
    kind = KINDS[seed % len(KINDS)]
    size = rng.uniform(0.02, 0.06)
    obj, target = helpers.random_object(rng, kind, size)
    hand = helpers.random_hand(rng, size)
    return kind, obj, target, hand, helpers.safe_start(rng, obj, hand, target)


RULES = ["paper", "hug"]


def assert_design_properties(traj: hugger.Trajectory, hand: hugger.Hand) -> None:
    """The invariants of docs/algorithm.md, from the trajectory alone."""
    J, P, ts, phase = traj.joints, traj.palm_pose, traj.tip_state, traj.phase
    # link lengths are exact
    lengths = np.linalg.norm(np.diff(J, axis=2), axis=-1)
    np.testing.assert_allclose(lengths, np.broadcast_to(hand.link_lengths, lengths.shape), rtol=1e-9)
    # every tail sits on its root
    roots = np.stack([hand.roots(p) for p in P])
    assert np.abs(J[:, :, 0] - roots).max() < 1e-9
    # each finger stays in its plane
    normal = P[:, :3, 2]
    for m, phi in enumerate(hand.finger_angles):
        u = P[:, :3, :3] @ np.array([np.cos(phi), np.sin(phi), 0.0])
        n = np.cross(normal, u)
        off = np.einsum("kni,ki->kn", J[:, m] - roots[:, m, None], n)
        assert np.abs(off).max() < 1e-9
    # TipState only goes FROZEN -> CONTACT -> DONE
    assert np.all(np.diff(ts.astype(int), axis=0) >= 0)
    # in Phase 2 the palm only translates along p, never backward, at most one step
    step = traj.params["step"]
    two = np.flatnonzero(phase == 2)
    for k in two[1:]:
        assert np.array_equal(P[k, :3, :3], P[k - 1, :3, :3])
        dp = P[k, :3, 3] - P[k - 1, :3, 3]
        along = dp @ normal[k]
        assert np.linalg.norm(dp - along * normal[k]) < 1e-12
        assert -1e-15 <= along <= step * (1 + 1e-9)
    assert phase[0] == 0 and np.all(np.diff(phase) >= 0)
    # DONE fingers keep their joint angles (they move only rigidly with the palm)
    for m in range(ts.shape[1]):
        done = np.flatnonzero(ts[:, m] == 2)
        if len(done):
            assert np.array_equal(traj.angles[done[0]:, m], np.broadcast_to(traj.angles[done[0], m], traj.angles[done[0]:, m].shape))
    # no configuration repeats the one before in Phase 2
    for k in two[1:]:
        assert not (np.array_equal(J[k], J[k - 1]) and np.array_equal(ts[k], ts[k - 1])), k


@pytest.mark.parametrize("rules", RULES)
@pytest.mark.parametrize("seed", SEEDS)
def test_random_case(seed, rules, checker, tmp_path):
    kind, obj, target, hand, start = random_case(seed)
    planner = hugger.Planner(hand, obj, target, start, rules=rules)
    traj = planner.plan()
    assert traj.status == "done", (kind, hand, planner.stats)
    assert_design_properties(traj, hand)
    helpers.save_and_check(checker, traj, tmp_path / "plan.npz", samples=40, motion=True)


MESHES = helpers.ycb_paths()


@pytest.mark.skipif(not MESHES, reason=helpers.SHARED_MISSING)
@pytest.mark.parametrize("rules", RULES)
@pytest.mark.parametrize("path", MESHES, ids=[p.stem for p in MESHES])
def test_real_mesh(path, rules, checker, tmp_path):
    v, f = helpers.read_obj(path)
    if path.stem == "ycb_mug":  # left as scanned: not closed (SOURCES.md); it must be refused clearly
        with pytest.raises(ValueError, match="degenerate|not closed|manifold"):
            hugger.Object(v, f)
        return
    obj = hugger.Object(v, f)
    target = obj.centroid
    assert obj.inside(target)
    rng = np.random.default_rng(len(path.stem))
    hand = hugger.Hand()
    planner = hugger.Planner(hand, obj, target, helpers.safe_start(rng, obj, hand, target), rules=rules)
    traj = planner.plan()
    assert traj.status == "done", planner.stats
    assert_design_properties(traj, hand)
    helpers.save_and_check(checker, traj, tmp_path / "plan.npz", samples=30, motion=True)
    assert json.loads(traj.stats_json)["phase2_iterations"] > 0
