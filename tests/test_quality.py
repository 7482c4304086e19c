"""The compiled grasp quality (Qhull in C++) against a slow reference built on scipy's Qhull."""
from __future__ import annotations

import time

import numpy as np
import pytest

import hugger
import hugger.analysis as A
from helpers import random_rotation

scipy_spatial = pytest.importorskip("scipy.spatial", reason="the reference implementation needs scipy")

CLOSURE_TOL = 1e-9


def reference_quality(points, normals, center, mu, cone_edges, torque_scale):
    """The definition, step by step, with scipy: (force_closure, epsilon, volume, wrenches)."""
    w = A.primitive_wrenches(points, normals, center, mu, cone_edges, torque_scale)
    _, first = np.unique(np.round(w, 10), axis=0, return_index=True)
    w = w[np.sort(first)]
    if w.shape[0] < 7:
        return False, 0.0, 0.0, w.shape[0]
    spread = np.linalg.svd(w - w.mean(axis=0), compute_uv=False)
    if spread[-1] <= 1e-9 * max(spread[0], 1e-300):
        return False, 0.0, 0.0, w.shape[0]
    try:
        hull = scipy_spatial.ConvexHull(w, qhull_options="QJ")
    except (scipy_spatial.QhullError, ValueError):
        return False, 0.0, 0.0, w.shape[0]
    eps = float((-hull.equations[:, -1]).min())
    closure = eps > CLOSURE_TOL * float(np.abs(w).max())
    return bool(closure), eps if closure else 0.0, float(hull.volume), w.shape[0]


def random_grasp(rng: np.random.Generator):
    """Contacts on a random ellipsoid-like surface: a few to a few dozen, some shared, some flat sets."""
    kind = rng.integers(4)
    c = int(rng.integers(2, 13))
    d = rng.normal(size=(c, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    if kind == 1:  # one-sided: contacts on a cap only (often no closure)
        d[:, 2] = np.abs(d[:, 2]) + 0.5
        d /= np.linalg.norm(d, axis=1, keepdims=True)
    radii = rng.uniform(0.02, 0.06, size=3)
    points = d * radii
    normals = d / radii**2
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    if kind == 2:  # coplanar: every contact in the plane z = 0
        points[:, 2] = 0.0
        normals[:, 2] = 0.0
        ok = np.linalg.norm(normals, axis=1) > 1e-6
        points, normals = points[ok], normals[ok] / np.linalg.norm(normals[ok], axis=1, keepdims=True)
        if len(points) == 0:
            points, normals = np.array([[0.03, 0, 0]]), np.array([[1.0, 0, 0]])
    if kind == 3 and len(points) > 2:  # shared contacts (the ends of adjacent links)
        points = np.concatenate([points, points[:2]])
        normals = np.concatenate([normals, normals[:2]])
    rot = random_rotation(rng)
    shift = rng.uniform(-0.1, 0.1, size=3)
    center = rng.uniform(-0.005, 0.005, size=3) + shift
    mu = float(rng.choice([0.0, 0.3, 0.5, 1.0]))
    edges = int(rng.choice([4, 6, 8]))
    return points @ rot.T + shift, normals @ rot.T, center, mu, edges, float(radii.max())


def test_compiled_quality_matches_the_reference_on_500_random_grasps():
    rng = np.random.default_rng(20261201)
    closures = 0
    for i in range(500):
        points, normals, center, mu, edges, scale = random_grasp(rng)
        ref = reference_quality(points, normals, center, mu, edges, scale)
        contacts = A.Contacts.from_arrays(points, normals)
        q = A.grasp_quality(contacts, center, mu=mu, cone_edges=edges, torque_scale=scale)
        fast = A.grasp_quality(contacts, center, mu=mu, cone_edges=edges, torque_scale=scale, volume=False)
        for r in (q, fast):
            assert r.wrenches == ref[3], i
            assert r.force_closure == ref[0], (i, r, ref)
            assert r.epsilon == pytest.approx(ref[1], rel=1e-6, abs=1e-12), (i, r, ref)
        assert q.volume == pytest.approx(ref[2], rel=1e-6, abs=1e-15), (i, q, ref)
        assert fast.volume == 0.0
        closures += ref[0]
    assert 100 < closures < 450  # both verdicts well represented


def test_compiled_quality_matches_the_reference_on_real_plans(hand):
    obj = hugger.objects.get("curvy")
    case = hugger.scenarios.default_case("curvy", hand)
    traj = hugger.Planner(hand, obj, case.target, case.palm_pose).plan()
    found = A.contacts(traj, obj=obj)
    scale = float(np.linalg.norm(obj.vertices - traj.target, axis=1).max())
    for mu in (0.0, 0.5, 1.0):
        ref = reference_quality(found.points, found.normals, traj.target, mu, 8, scale)
        q = A.grasp_quality(found, traj.target, mu=mu, obj=obj)
        fast = A.grasp_quality(found, traj.target, mu=mu, obj=obj, volume=False)
        assert (q.force_closure, q.wrenches) == (ref[0], ref[3]) == (fast.force_closure, fast.wrenches)
        assert q.epsilon == pytest.approx(ref[1], rel=1e-6, abs=1e-12)
        assert fast.epsilon == pytest.approx(ref[1], rel=1e-6, abs=1e-12)
        assert q.volume == pytest.approx(ref[2], rel=1e-6)


def test_compiled_quality_is_deterministic_across_threads():
    from concurrent.futures import ThreadPoolExecutor

    rng = np.random.default_rng(7)
    grasps = [random_grasp(rng) for _ in range(40)]

    def run(g):
        p, n, c, mu, e, s = g
        q = hugger._core.grasp_quality(p, n, c, mu, e, s, True)
        f = hugger._core.grasp_quality(p, n, c, mu, e, s, False)
        return (q.force_closure, q.epsilon, q.volume, q.wrenches, f.epsilon)

    serial = [run(g) for g in grasps]
    time.sleep(1.1)  # a time-seeded joggle would differ now
    with ThreadPoolExecutor(4) as pool:
        parallel = list(pool.map(run, grasps * 3))
    assert parallel == serial * 3


def test_compiled_quality_rejects_bad_input():
    p = np.zeros((8, 3))
    n = np.tile([1.0, 0.0, 0.0], (8, 1))
    with pytest.raises(ValueError, match="normals"):
        hugger._core.grasp_quality(p, n[:5], np.zeros(3))
    with pytest.raises(ValueError, match="cone_edges"):
        hugger._core.grasp_quality(p, n, np.zeros(3), 0.5, 2, 1.0)
    with pytest.raises(ValueError, match="torque_scale"):
        hugger._core.grasp_quality(p, n, np.zeros(3), 0.5, 8, 0.0)
    with pytest.raises(ValueError, match="finite"):
        hugger._core.grasp_quality(np.full((8, 3), np.nan), n, np.zeros(3))
    with pytest.raises(ValueError, match="zero"):
        hugger._core.grasp_quality(p, np.zeros((8, 3)), np.zeros(3))
    with pytest.raises(ValueError, match="shape"):
        hugger._core.grasp_quality(np.zeros((8, 2)), n, np.zeros(3))
    empty = hugger._core.grasp_quality(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(3))
    assert not empty.force_closure and empty.epsilon == 0.0 and empty.wrenches == 0
