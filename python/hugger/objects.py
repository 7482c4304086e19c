"""Built-in test objects: closed, outward-oriented meshes generated with numpy.

Each function returns a :class:`hugger.Object` centred at ``center`` (default the origin),
so the centre is a natural target point T. Sizes are in metres.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from .world import Object


def icosphere(subdivisions: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Unit sphere: vertices (V, 3) and outward faces (F, 3); F = 20 * 4**subdivisions."""
    t = (1.0 + 5 ** 0.5) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7),
         (9, 8, 1)]
    verts = [np.array(p, dtype=float) / np.linalg.norm(p) for p in v]
    faces = f
    for _ in range(int(subdivisions)):
        cache: dict[tuple[int, int], int] = {}

        def mid(a: int, b: int) -> int:
            key = (min(a, b), max(a, b))
            if key not in cache:
                p = verts[a] + verts[b]
                verts.append(p / np.linalg.norm(p))
                cache[key] = len(verts) - 1
            return cache[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return np.array(verts), np.array(faces, dtype=np.int64)


def _center(center: Any) -> np.ndarray:
    c = np.asarray(center, dtype=np.float64).reshape(3)
    if not np.all(np.isfinite(c)):
        raise ValueError("center must be finite")
    return c


def sphere(radius: float = 0.04, center: Any = (0, 0, 0), subdivisions: int = 4) -> Object:
    """Sphere of ``radius`` (default 4 cm), 20 * 4**subdivisions triangles."""
    v, f = icosphere(subdivisions)
    return Object(v * float(radius) + _center(center), f)


def ellipsoid(radii: Any = (0.05, 0.04, 0.03), center: Any = (0, 0, 0), subdivisions: int = 4) -> Object:
    """Axis-aligned ellipsoid with semi-axes ``radii`` (default 5 x 4 x 3 cm)."""
    v, f = icosphere(subdivisions)
    return Object(v * np.asarray(radii, dtype=np.float64).reshape(3) + _center(center), f)


def blob(radius: float = 0.04, amplitude: float = 0.25, seed: int = 0, center: Any = (0, 0, 0),
         subdivisions: int = 4) -> Object:
    """A smooth, non-convex, star-shaped body: a sphere whose radius varies by a few low-order
    waves of relative ``amplitude`` (random phases from ``seed``)."""
    v, f = icosphere(subdivisions)
    rng = np.random.default_rng(seed)
    scale = np.ones(len(v))
    for _ in range(4):
        k = rng.normal(size=3)
        k *= rng.uniform(2.0, 4.0) / np.linalg.norm(k)
        scale += amplitude / 4 * np.sin(v @ k + rng.uniform(0, 2 * np.pi))
    scale = np.maximum(scale, 0.4)
    return Object(v * (radius * scale)[:, None] + _center(center), f)


def box(extents: Any = (0.06, 0.05, 0.04), center: Any = (0, 0, 0), divisions: int = 4) -> Object:
    """Axis-aligned box of full ``extents`` (default 6 x 5 x 4 cm), each face a grid of
    ``divisions`` x ``divisions`` squares."""
    n = max(1, int(divisions))
    e = np.asarray(extents, dtype=np.float64).reshape(3) / 2.0
    verts: dict[tuple[int, int, int], int] = {}
    points: list[np.ndarray] = []
    faces: list[tuple[int, int, int]] = []

    def vid(ijk: tuple[int, int, int]) -> int:
        if ijk not in verts:
            verts[ijk] = len(points)
            points.append((np.array(ijk, dtype=float) / n * 2.0 - 1.0) * e)
        return verts[ijk]

    for axis in range(3):
        for side in (0, n):
            a1, a2 = (axis + 1) % 3, (axis + 2) % 3
            for i in range(n):
                for j in range(n):
                    quad = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        ijk = [0, 0, 0]
                        ijk[axis], ijk[a1], ijk[a2] = side, i + di, j + dj
                        quad.append(vid(tuple(ijk)))
                    if side == 0:
                        quad = quad[::-1]
                    faces += [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]
    return Object(np.array(points) + _center(center), np.array(faces, dtype=np.int64))


def cylinder(radius: float = 0.035, height: float = 0.1, center: Any = (0, 0, 0), sections: int = 48,
             rings: int = 8) -> Object:
    """Cylinder along z of ``radius`` and ``height`` (default 3.5 x 10 cm), closed by flat caps."""
    s, r = max(3, int(sections)), max(1, int(rings))
    ang = 2 * np.pi * np.arange(s) / s
    pts = [np.array([0.0, 0.0, -height / 2]), np.array([0.0, 0.0, height / 2])]
    for k in range(r + 1):
        z = -height / 2 + height * k / r
        pts += [np.array([radius * np.cos(a), radius * np.sin(a), z]) for a in ang]
    ring = lambda k, i: 2 + k * s + (i % s)  # noqa: E731
    faces = []
    for i in range(s):
        faces.append((0, ring(0, i + 1), ring(0, i)))
        faces.append((1, ring(r, i), ring(r, i + 1)))
        for k in range(r):
            faces += [(ring(k, i), ring(k, i + 1), ring(k + 1, i + 1)), (ring(k, i), ring(k + 1, i + 1), ring(k + 1, i))]
    return Object(np.array(pts) + _center(center), np.array(faces, dtype=np.int64))
