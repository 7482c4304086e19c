"""Analytic skins: a sphere, a box and a union of spheres given by formulas, no mesh.

They are examples of a skin written in Python (docs/skins.md) and references for tests: a plan
made with one agrees with a plan made on a fine mesh of the same shape. Each has ``mesh()``, a
:class:`hugger.Object` of its shape, to record with the plan (``Planner(..., record_object=)``)
and to check it against.

Conventions (every skin's): metres, world frame, gaps signed (negative inside the object), exact
when at most the query's ``cap`` for a capsule whose axis stays outside the object. Where a
capsule's axis enters the object, the gap is at most ``-radius`` (its depth is not measured), as
in the mesh world.
"""
from __future__ import annotations

import math
from typing import Any, Callable, cast

import numpy as np

from .._checks import positive
from .._core import Sensing, Touch

_UP = np.array([0.0, 0.0, 1.0])


def _vector(name: str, value: Any) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be a finite 3-vector, got {value!r}")
    return v


def _nearest_on_segment(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Nearest points of the segment [a, b] (3,) to the points c (k, 3): (k, 3)."""
    ab = b - a
    length2 = float(ab @ ab)
    if length2 == 0.0:
        return np.broadcast_to(a, c.shape).copy()
    t = np.clip((c - a) @ ab / length2, 0.0, 1.0)
    return cast(np.ndarray, a + t[:, None] * ab)


def _palm_frame(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (k, 3) in the palm frame P (z along the palm normal, origin on the front face)."""
    return cast(np.ndarray, (points - pose[:3, 3]) @ pose[:3, :3])


def _disk_distance(q: np.ndarray, radius: float, thickness: float) -> np.ndarray:
    """Signed distance (k,) of points q (k, 3), in the palm frame, to the solid palm disk
    (rho <= radius, -thickness <= z <= 0); negative inside."""
    rho = np.hypot(q[:, 0], q[:, 1])
    dr = rho - radius
    dz = np.maximum(q[:, 2], -thickness - q[:, 2])  # > 0 outside the slab
    outside = np.hypot(np.maximum(dr, 0.0), np.maximum(dz, 0.0))
    inside = np.minimum(np.maximum(dr, dz), 0.0)
    return cast(np.ndarray, outside + inside)


class SpheresSkin(Sensing):
    """The union of spheres ``centers`` (k, 3) of ``radii`` (k,) (m), by formulas.

    The gap of a capsule is its smallest gap to any one sphere: exact while the capsule is
    outside the union (inside it, negative)."""

    def __init__(self, centers: Any, radii: Any) -> None:
        super().__init__()
        c = np.asarray(centers, dtype=np.float64)
        r = np.asarray(radii, dtype=np.float64).reshape(-1)
        if c.ndim != 2 or c.shape[1] != 3 or len(c) == 0 or not np.all(np.isfinite(c)):
            raise ValueError(f"centers must be a finite (k, 3) array with k >= 1, got shape {c.shape}")
        if r.shape != (len(c),) or not np.all(np.isfinite(r)) or not np.all(r > 0):
            raise ValueError(f"radii must be ({len(c)},) positive finite numbers (m), got {radii!r}")
        self.centers, self.radii = c, r

    def capsule(self, a: np.ndarray, b: np.ndarray, radius: float, cap: float = math.inf) -> Touch:  # type: ignore[override]
        p = _nearest_on_segment(a, b, self.centers)
        d = p - self.centers
        dist = np.sqrt(np.einsum("ij,ij->i", d, d))
        gaps = dist - self.radii - radius
        i = int(np.argmin(gaps))
        if dist[i] > 0.0:
            normal = d[i] / dist[i]
        else:  # the axis passes through the centre: any direction normal to it
            axis = b - a
            normal = np.cross(axis, _UP) if np.linalg.norm(np.cross(axis, _UP)) > 1e-12 * np.linalg.norm(axis) else _UP
            normal = normal / np.linalg.norm(normal)
        return Touch(float(gaps[i]), p[i], self.centers[i] + self.radii[i] * normal, normal)

    def palm(self, pose: np.ndarray, radius: float, thickness: float, cap: float = math.inf) -> float:  # type: ignore[override]
        q = _palm_frame(pose, self.centers)
        return float(np.min(_disk_distance(q, radius, thickness) - self.radii))

    def signed_distance(self, points: Any) -> np.ndarray:
        """Signed distance (n,) of points (n, 3) to the union (exact outside it)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        d = np.linalg.norm(p[:, None, :] - self.centers[None], axis=2) - self.radii[None]
        return cast(np.ndarray, d.min(axis=1))

    def mesh(self, subdivisions: int = 6) -> Any:
        """A closed mesh of the union, star-shaped about the first centre: every sphere must
        contain it. Vertices lie on the surface (a ray from the centre leaves the union where it
        leaves the last sphere)."""
        from ..objects import _star, icosphere

        o = self.centers[0]
        if np.any(np.linalg.norm(self.centers - o, axis=1) >= self.radii):
            raise ValueError("mesh() needs every sphere to contain the first centre (a star-shaped union)")
        v, f = icosphere(subdivisions)
        oc = o - self.centers  # (k, 3)
        b = v @ oc.T  # (n, k): u . (o - c)
        cc = np.einsum("ij,ij->i", oc, oc) - self.radii**2  # < 0: o inside each sphere
        rho = (-b + np.sqrt(b**2 - cc[None])).max(axis=1)
        return _star(v, f, rho, o)


class SphereSkin(SpheresSkin):
    """A sphere of ``radius`` (m) about ``center`` (3,), by formulas (the skin the documentation
    writes step by step)."""

    def __init__(self, radius: float = 0.04, center: Any = (0.0, 0.0, 0.0)) -> None:
        super().__init__(np.asarray(_vector("center", center))[None], [positive("radius", radius)])
        self.radius, self.center = float(self.radii[0]), self.centers[0]

    def mesh(self, subdivisions: int = 6) -> Any:
        from .. import objects

        return objects.sphere(radius=self.radius, center=self.center, subdivisions=subdivisions)


def _gjk_distance(support: Callable[[np.ndarray], np.ndarray], tolerance: float = 1e-11,
                  iterations: int = 100) -> float:
    """Distance from the origin to a convex set given by its support function (GJK with an exact
    sub-simplex search); 0 when the origin is inside."""
    v: np.ndarray | None
    v = support(np.array([1.0, 0.0, 0.0]))
    simplex = [v]
    for _ in range(iterations):
        vv = float(v @ v)
        if vv <= 1e-28:
            return 0.0
        w = support(-v)
        if vv - float(v @ w) <= tolerance * math.sqrt(vv):
            return math.sqrt(vv)
        simplex.append(w)
        v, simplex = _closest_subsimplex(simplex)
        if v is None:
            return 0.0
    return math.sqrt(float(v @ v))


def _closest_subsimplex(points: list[np.ndarray]) -> tuple[np.ndarray | None, list[np.ndarray]]:
    """The point of the simplex nearest the origin and the smallest face holding it; (None, _)
    when the origin lies inside a full tetrahedron."""
    n = len(points)
    P = np.array(points)
    best, best_set = None, None
    for mask in range(1, 1 << n):
        idx = [i for i in range(n) if mask >> i & 1]
        k = len(idx)
        Q = P[idx]
        if k == 1:
            lam = np.ones(1)
        else:  # x = q0 + D^T mu nearest the origin: (D D^T) mu = -D q0, D the edges from q0
            D = Q[1:] - Q[0]
            G = D @ D.T
            if np.linalg.cond(G) > 1e12:
                continue  # a degenerate face: its points are covered by its smaller faces
            mu = np.linalg.solve(G, -D @ Q[0])
            lam = np.concatenate(([1.0 - mu.sum()], mu))
        if np.any(lam < -1e-12) or not np.all(np.isfinite(lam)):
            continue
        x = lam @ Q
        if k == 4:
            return None, points  # the origin is inside the tetrahedron
        d = float(x @ x)
        if best is None or d < best[0] - 1e-30:
            best, best_set = (d, x), [points[i] for i in idx]
    if best is None:  # degenerate: keep the nearest vertex
        i = int(np.argmin(np.einsum("ij,ij->i", P, P)))
        return P[i], [points[i]]
    return best[1], cast(list[np.ndarray], best_set)


class BoxSkin(Sensing):
    """A box of full ``extents`` (3,) (m) about ``center``, its edges along the columns of
    ``rotation`` (3, 3; default the world axes), by formulas."""

    def __init__(self, extents: Any = (0.06, 0.05, 0.04), center: Any = (0.0, 0.0, 0.0), rotation: Any = None) -> None:
        super().__init__()
        e = _vector("extents", extents)
        if not np.all(e > 0):
            raise ValueError(f"extents must be positive (m), got {extents!r}")
        R = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)
        if R.shape != (3, 3) or not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
            raise ValueError("rotation must be a (3, 3) rotation matrix")
        self.extents, self.center, self.rotation = e, _vector("center", center), R
        self.half = 0.5 * e

    def capsule(self, a: np.ndarray, b: np.ndarray, radius: float, cap: float = math.inf) -> Touch:  # type: ignore[override]
        R, c, h = self.rotation, self.center, self.half
        qa, d = (a - c) @ R, (b - a) @ R
        # |p(t) - box|^2 is a quadratic on each interval between the slab crossings of p(t).
        ts = [0.0, 1.0]
        for i in range(3):
            if d[i] != 0.0:
                for bound in (-h[i], h[i]):
                    t = (bound - qa[i]) / d[i]
                    if 0.0 < t < 1.0:
                        ts.append(t)
        ts.sort()
        best, best_t, inside_t = math.inf, 0.0, None
        for t0, t1 in zip(ts[:-1], ts[1:]):
            pm = qa + 0.5 * (t0 + t1) * d
            target = np.clip(pm, -h, h)
            clamped = pm != target
            if not clamped.any():
                inside_t = 0.5 * (t0 + t1)
                break
            dc, oc = d[clamped], (qa - target)[clamped]
            den = float(dc @ dc)
            t = t0 if den == 0.0 else min(max(-float(oc @ dc) / den, t0), t1)
            value = float(np.sum((oc + t * dc) ** 2))
            if value < best:
                best, best_t = value, t
        if inside_t is not None:  # the axis enters the box: depth at that point, not measured exactly
            p = qa + inside_t * d
            depth = h - np.abs(p)
            i = int(np.argmin(depth))
            n = np.zeros(3)
            n[i] = 1.0 if p[i] >= 0 else -1.0
            on_box = p.copy()
            on_box[i] = n[i] * h[i]
            return Touch(-float(depth[i]) - radius, c + R @ p, c + R @ on_box, R @ n)
        p = qa + best_t * d
        on_box = np.clip(p, -h, h)
        diff = p - on_box
        dist = math.sqrt(float(diff @ diff))
        if dist > 0.0:
            n = diff / dist
        else:  # touching the surface: the normal of the face it touches
            i = int(np.argmax(np.abs(p) - h))
            n = np.zeros(3)
            n[i] = 1.0 if p[i] >= 0 else -1.0
        return Touch(dist - radius, c + R @ p, c + R @ on_box, R @ n)

    def palm(self, pose: np.ndarray, radius: float, thickness: float, cap: float = math.inf) -> float:  # type: ignore[override]
        z = pose[:3, 2]
        centre = pose[:3, 3] - 0.5 * thickness * z
        R, c, h = self.rotation, self.center, self.half

        def support(u: np.ndarray) -> np.ndarray:  # of the cylinder minus the box
            uz = float(u @ z)
            perp = u - uz * z
            norm = math.sqrt(float(perp @ perp))
            # Along the axis (perp is rounding noise) any point of the face supports: its centre.
            radial = radius / norm * perp if norm > 1e-9 * math.sqrt(float(u @ u)) else 0.0
            s_cyl = centre + math.copysign(0.5 * thickness, uz) * z + radial
            s_box = c + R @ (np.where(-u @ R >= 0.0, h, -h))
            return s_cyl - s_box

        d = _gjk_distance(support)
        return d if d > 0.0 else -np.finfo(np.float64).tiny  # overlapping: negative (depth not measured)

    def signed_distance(self, points: Any) -> np.ndarray:
        """Signed distance (n,) of points (n, 3) to the box."""
        q = np.abs((np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.center) @ self.rotation) - self.half
        return cast(np.ndarray, np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0))

    def mesh(self, divisions: int = 4) -> Any:
        """The box as a :class:`hugger.Object` (exact: a box mesh is the box)."""
        from .. import objects

        if np.allclose(self.rotation, np.eye(3)):
            return objects.box(extents=self.extents, center=self.center, divisions=divisions)
        from ..world import Object

        obj = objects.box(extents=self.extents, center=(0.0, 0.0, 0.0), divisions=divisions)

        return Object(obj.vertices @ self.rotation.T + self.center, obj.faces)
