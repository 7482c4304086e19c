"""The world: Object meshes, their queries (inside, distances, sections) and mesh refusals."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import helpers
import hugger
from hugger import objects, scenarios
from helpers import ico, no_warnings
from hugger.hand import PLAUSIBLE_SIZE
from hugger.world import MAX_COORDINATE

HERE = Path(__file__).resolve()


# --- object -------------------------------------------------------------------------------

def test_object_queries(fine_sphere):
    assert fine_sphere.inside([0, 0, 0]) and not fine_sphere.inside([0.05, 0, 0])
    assert fine_sphere.signed_distance([0.05, 0, 0]) == pytest.approx(0.01, abs=3e-4)
    assert fine_sphere.volume == pytest.approx(4 / 3 * np.pi * 0.04 ** 3, rel=0.01)
    loops = fine_sphere.section([0, 0, 0], [1, 0, 0], [0, 1, 0])
    assert len(loops) == 1 and np.linalg.norm(loops[0], axis=1) == pytest.approx(0.04, abs=3e-4)


def test_closest_within_a_distance_is_exact_there_and_skips_the_rest(fine_sphere):
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(400, 3)) * 0.03
    full = fine_sphere.closest(pts)
    near = fine_sphere.closest(pts, max_distance=0.005)
    within = np.abs(full["distance"]) <= 0.005
    assert within.any() and (~within).any()
    for key in ("distance", "point", "normal", "triangle"):
        assert np.array_equal(near[key][within], full[key][within]), key
    # the rest: skipped (infinite, signed as before, no point) or found all the same
    skipped = near["triangle"] == -1
    assert not skipped[within].any() and skipped.any()
    assert np.all(np.isinf(near["distance"][skipped]))
    assert np.array_equal(np.sign(near["distance"][skipped]), np.sign(full["distance"][skipped]))
    assert np.all(np.isnan(near["point"][skipped])) and np.all(np.isnan(near["normal"][skipped]))
    assert np.array_equal(near["distance"][~skipped], full["distance"][~skipped])
    for bad in (-1.0, float("nan"), None, "near"):
        with pytest.raises(ValueError, match="max_distance"):
            fine_sphere.closest(pts, max_distance=bad)


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


# --- objects: bad meshes ---------------------------------------------------------------------

def _pillow(v, f):
    """The sphere plus a zero-volume 'pillow': face 0's triangle twice over three new vertices."""
    n = len(v)
    return np.vstack([v, v[f[0]]]), np.vstack([f, [[n, n + 1, n + 2], [n, n + 2, n + 1]]])


def _pillow_apart(v, f):
    """The sphere plus a pillow over three new vertices of their own (no coincident vertices):
    the same triangle twice over the same indices, in opposite turns."""
    n = len(v)
    return np.vstack([v, 1.5 * v[f[0]]]), np.vstack([f, [[n, n + 1, n + 2], [n, n + 2, n + 1]]])


def _pillow_on_the_sphere(v, f):
    """A pillow over three pairwise non-adjacent vertices of the sphere itself."""
    adjacent = {frozenset(e) for tri in f.tolist() for e in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0]))}
    pick = [0]
    for i in range(1, len(v)):
        if all(frozenset((i, j)) not in adjacent for j in pick):
            pick.append(i)
        if len(pick) == 3:
            break
    a, b, c = pick
    return v, np.vstack([f, [[a, b, c], [a, c, b]]])


def _kissing_spheres(v, f):
    """Two spheres that share one vertex: a non-manifold vertex."""
    i, j = int(np.argmax(v[:, 0])), int(np.argmin(v[:, 0]))
    v2 = v - v[j] + v[i]  # the second sphere's vertex j sits on the first's vertex i
    f2 = f + len(v)
    f2[f2 == j + len(v)] = i
    return np.vstack([v, v2]), np.vstack([f, f2])


def _tets_sharing_an_edge(v, f):
    """Two tetrahedra sharing one edge: four faces meet at it (a non-manifold edge)."""
    a, b = [0, 0, 0], [0.02, 0, 0]
    verts = np.array([a, b, [0.01, 0.02, 0.0], [0.01, 0.01, 0.02], [0.01, -0.02, 0.0], [0.01, -0.01, -0.02]])
    tet = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    t2 = tet.copy()
    t2[t2 == 2], t2[t2 == 3] = 4, 5
    t2 = t2[:, [0, 2, 1]]  # the mirrored tetrahedron: keep its normals outward
    return verts, np.vstack([tet, t2])


def _move(v, f, i, where):
    v = v.copy()
    v[i] = where
    return v, f


@pytest.mark.parametrize("make, match", [
    # empty
    (lambda v, f: (v, f[:0]), "empty"),
    (lambda v, f: (v[:0], f), "empty"),
    (lambda v, f: ([], []), r"\(V, 3\)"),
    (lambda v, f: (None, f), "vertices"),
    (lambda v, f: (v, None), "faces"),
    # not finite, or absurdly far
    (lambda v, f: _move(v, f, 0, [-np.inf, 0, 0]), "vertex 0 is not finite"),
    (lambda v, f: (np.vstack([v, [np.nan, 0, 0]]), f), f"vertex {162} is not finite"),  # even unreferenced
    (lambda v, f: (v * 1e300, f), "beyond"),
    (lambda v, f: _move(v, f, 5, [2 * MAX_COORDINATE, 0, 0]), "vertex 5 .* beyond"),
    # indices out of range, negative, wrapped or not whole
    (lambda v, f: (v, np.where(f == f.max(), len(v), f)), f"indexes vertex {162}, outside 0..161"),
    (lambda v, f: (v, np.where(f == 0, -3, f)), "indexes vertex -3, outside"),
    (lambda v, f: (v, np.where(f == 0, np.uint64(2 ** 63), f.astype(np.uint64))),
     "indexes vertex 9223372036854775808, outside"),  # not wrapped to a negative int64
    (lambda v, f: (v, np.where(f == 0, 1e30, f.astype(float))), "outside"),
    (lambda v, f: (v, np.where(f == 0, np.nan, f.astype(float))), "whole-number"),
    (lambda v, f: (v, f.astype(bool)), "whole-number"),
    (lambda v, f: (v, f.astype(complex)), "whole-number"),
    (lambda v, f: (v, f.astype(str)), "whole-number"),
    # not real numbers
    (lambda v, f: (v.astype(complex), f), "real numbers"),
    (lambda v, f: (v.astype(str), f), "real numbers"),
    (lambda v, f: (np.array([[None, 0, 0]] + v[1:].tolist(), dtype=object), f), "real numbers, got None"),
    # degenerate (zero-area) triangles: coincident or collinear vertices
    (lambda v, f: _move(v, f, f[0, 0], v[f[0, 1]]), "degenerate: zero area"),
    (lambda v, f: _move(v, f, f[0, 0], (v[f[0, 1]] + v[f[0, 2]]) / 2), "degenerate: zero area"),
    # duplicate triangles
    (lambda v, f: (v, np.vstack([f, f[:1, [0, 2, 1]]])), "consistently oriented|manifold"),
    (_pillow, "same triangle"),
    (_pillow_apart, "same triangle"),
    (_pillow_on_the_sphere, "same triangle"),
    # open
    (lambda v, f: (v, f[1:-1]), "not closed"),
    (lambda v, f: (v[:3], [[0, 1, 2]]), "not closed"),
    # non-manifold
    (_kissing_spheres, "not manifold at vertex"),
    (_tets_sharing_an_edge, "manifold"),
    # inside-out, alone or as the only shell, and flat
    (lambda v, f: (np.vstack([v, 0.5 * v]), np.vstack([f[:, [0, 2, 1]], f[:, [0, 2, 1]] + len(v)])), "inward"),
    (lambda v, f: (v * [1, 1, 0], f), "degenerate|non-positive volume"),
])
def test_object_refuses_bad_meshes(make, match):
    v, f = ico()
    with pytest.raises(ValueError, match=match):
        hugger.Object(*make(v, f))


def test_object_accepts_valid_meshes_the_checks_must_not_refuse():
    v, f = ico()
    n = len(v)
    # a hollow ball (inner shell inward), two disjoint balls, float indices, nested balls
    no_warnings(hugger.Object, np.vstack([v, 0.5 * v]), np.vstack([f, f[:, [0, 2, 1]] + n]))
    no_warnings(hugger.Object, np.vstack([v, v + [0.1, 0, 0]]), np.vstack([f, f + n]))
    no_warnings(hugger.Object, v, f.astype(float))
    no_warnings(hugger.Object, v.astype(np.float32), f.astype(np.int32))
    for path in helpers.ycb_paths()[:3]:  # real scans, where present
        no_warnings(hugger.Object, *helpers.read_obj(path))


@pytest.mark.parametrize("offset", [1e3, 1e5, 5e5])
def test_inside_out_mesh_far_from_the_origin_is_refused(offset):
    v, f = ico(1, radius=0.1)
    with pytest.raises(ValueError, match="inward"):
        hugger.Object(v + offset, f[:, ::-1])
    obj = hugger.Object(v + offset, f)  # the right way out: accepted, and inside is right
    np.testing.assert_array_equal(obj.inside(offset + np.array([[0, 0, 0], [0, 0, 0.2]])), [True, False])


def test_volume_far_from_the_origin_is_accurate():
    v, f = ico(1, radius=0.1)
    near, far = hugger.Object(v, f).volume, hugger.Object(v + 5e5, f).volume
    assert far == pytest.approx(near, rel=1e-6)


@pytest.mark.xfail(strict=True, reason="known limitation, documented in docs/python.md: self-intersecting meshes are not "
                                       "detected, so this one is accepted and inside() answers True for points outside it")
def test_self_intersecting_mesh_is_refused():
    v, f = ico()
    v[0] = -1.6 * v[0]  # one vertex pushed out through the far side of the ball
    with pytest.raises(ValueError, match="intersect"):
        obj = hugger.Object(v, f)
        assert not obj.inside([0.0500366, -0.06529802, 0.03215176])  # outside (winding number 0)


def test_object_keeps_a_private_read_only_copy():
    v, f = ico()
    obj = hugger.Object(v, f)
    v[:] = 0.0
    assert obj.vertices.max() > 0.03
    with pytest.raises(ValueError):
        obj.vertices[0, 0] = 1.0


# --- implausible sizes: a UserWarning, pointing at the caller --------------------------------

@pytest.mark.parametrize("scale, words", [(1000.0, "millimetres"), (100.0, "millimetres"), (1e-2, "small")])
def test_object_of_implausible_size_warns_at_the_caller(scale, words):
    v, f = ico()
    with pytest.warns(UserWarning, match=f"implausibly .*{words}|{words}") as rec:
        obj = hugger.Object(v * scale, f)
    assert len(rec) == 1 and rec[0].filename == str(HERE)  # stacklevel: the user's line, not hugger's
    assert obj.volume > 0  # accepted all the same


def test_size_thresholds_are_the_documented_ones():
    lo, hi = PLAUSIBLE_SIZE
    assert (lo, hi) == (1e-3, 3.0)
    v, f = ico(radius=1.0)
    extent = lambda s: float(np.ptp(v * s, axis=0).max())  # noqa: E731
    no_warnings(hugger.Object, v * (0.99 * hi / extent(1.0)), f)
    with pytest.warns(UserWarning, match="large"):
        hugger.Object(v * (1.01 * hi / extent(1.0)), f)
    no_warnings(hugger.Object, v * (1.01 * lo / extent(1.0)), f)
    with pytest.warns(UserWarning, match="small"):
        hugger.Object(v * (0.99 * lo / extent(1.0)), f)


@pytest.mark.parametrize("far", [1e3, 1e9, 1e15, 1e300])
def test_points_far_outside_are_outside(far):
    # Far away every triangle is as near as any other to rounding: the answer must not depend on
    # which one the nearest search finds.
    o = hugger.objects.sphere(0.04)
    rng = np.random.default_rng(7)
    dirs = rng.normal(size=(20, 3))
    pts = far * dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    assert not o.inside(pts).any()
    assert (o.signed_distance(pts) > 0).all()
    assert (o.closest(pts)["distance"] > 0).all()


@pytest.mark.parametrize("method", ["inside", "signed_distance", "closest"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_query_points_must_be_finite(method, bad):
    o = hugger.objects.sphere(0.04)
    with pytest.raises(ValueError, match="points must be finite.*row 1"):
        getattr(o, method)([[0.0, 0.0, 0.0], [bad, 0.0, 0.0]])


def test_segment_distance_ends_must_be_finite():
    o = hugger.objects.sphere(0.04)
    with pytest.raises(ValueError, match="b must be finite"):
        o.segment_distance(np.zeros((1, 3)), np.array([[np.nan, 0.0, 0.0]]))


@pytest.mark.parametrize("call, name", [
    (lambda o, h: objects.sphere(radius="0.04"), "radius"),
    (lambda o, h: objects.sphere(radius=True), "radius"),
    (lambda o, h: objects.sphere(center=["0", "0", "0"]), "center"),
    (lambda o, h: hugger.look_at([0, 0, "0.2"], [0, 0, 0]), "position"),
    (lambda o, h: hugger.look_at([0, 0, 0.2], [0, 0, 0], up=[True, False, False]), "up"),
    (lambda o, h: o.inside(["0", "0", "0"]), "points"),
    (lambda o, h: o.closest([["0", "0", "0.1"]]), "points"),
    (lambda o, h: o.segment_distance([0, 0, 0.1], ["0", "0", "0.2"]), "b"),
    (lambda o, h: scenarios.start_pose(o, h, [0, 0, 0], turn_deg="10"), "turn_deg"),
    (lambda o, h: scenarios.start_pose(o, h, ["0", "0", "0"]), "target"),
    (lambda o, h: scenarios.start_pose(o, h, [0, 0, 0], distance="0.3"), "distance"),
    (lambda o, h: hugger.Planner(h, o, ["0", "0", "0"], np.eye(4)), "target"),
    (lambda o, h: hugger.search(h, o, pole=["0", "0", "1"], approaches=2), "pole"),
])
def test_numbers_given_as_text_are_refused_everywhere(call, name):
    # numpy and float() read "0.04" as a number and True as 1: every public entry refuses them
    # alike, as Hand(fingers="5") always did, naming the argument
    with pytest.raises(ValueError, match=f"^{name}( \\(--[a-z]+\\))? must be"):
        call(objects.sphere(), hugger.Hand())
