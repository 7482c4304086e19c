"""Objects to grasp: built-in shapes generated with numpy, and mesh files read with trimesh.

Each generator returns a closed, outward-oriented :class:`hugger.Object`. Sizes are in metres.
Every built-in has a natural target point T (the origin, except the torus, whose centre is not
inside it) and a default approach direction; ``get(name)`` builds one, ``BUILTINS`` lists them
and ``load(path)`` reads any mesh file trimesh reads (STL, OBJ, PLY, OFF, GLB), repairing it
when that is safe (see :func:`load`).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from . import _stable
from ._checks import positive, real_array, whole
from .world import MAX_COORDINATE, Object


#: The most subdivisions of the icosphere the generators take: 20 * 4**8 = 1,310,720 triangles.
MAX_SUBDIVISIONS = 8
#: The most triangles the box, cylinder and torus generators make.
MAX_TRIANGLES = 4_000_000


def _triangles(what: str, count: int) -> None:
    """A ValueError when a generator's counts would give more than MAX_TRIANGLES triangles."""
    if count > MAX_TRIANGLES:
        raise ValueError(f"{what} would have {count:,} triangles; at most {MAX_TRIANGLES:,} are made")


def icosphere(subdivisions: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Unit sphere: vertices (V, 3) and outward faces (F, 3); F = 20 * 4**subdivisions
    (``subdivisions`` a whole number from 0 to MAX_SUBDIVISIONS).

    Each vertex is normalised as p / sqrt(p.x*p.x + p.y*p.y + p.z*p.z), in that order: the same
    bits on every x86-64 processor with FMA (hugger._stable), and those of the benchmark's C++
    icosphere."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7),
         (9, 8, 1)]
    def unit(p: np.ndarray) -> np.ndarray:  # hugger._stable.norm's order, in scalars: 10k vertices
        x, y, z = (float(c) for c in p)
        return p / math.sqrt(x * x + y * y + z * z)

    levels = whole("subdivisions", subdivisions, 0, MAX_SUBDIVISIONS)
    verts = [unit(np.array(p, dtype=float)) for p in v]
    faces = f
    for _ in range(levels):
        cache: dict[tuple[int, int], int] = {}

        def mid(a: int, b: int) -> int:
            key = (min(a, b), max(a, b))
            if key not in cache:
                p = verts[a] + verts[b]
                verts.append(unit(p))
                cache[key] = len(verts) - 1
            return cache[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return np.array(verts), np.array(faces, dtype=np.int64)


def _three(name: str, value: Any) -> np.ndarray:
    """``value`` as 3 floats, or a ValueError naming ``name``."""
    try:
        return real_array(name, value).reshape(3)
    except ValueError:
        raise ValueError(f"{name} must be 3 numbers, got {value!r}") from None


def _center(center: Any) -> np.ndarray:
    c = _three("center", center)
    if not np.all(np.isfinite(c)):
        raise ValueError("center must be finite")
    return c


def _sizes(name: str, value: Any) -> np.ndarray:
    """``value`` as 3 sizes, each finite and positive (``positive``), or a ValueError naming ``name``."""
    return np.array([positive(name, v) for v in _three(name, value)])


def sphere(radius: float = 0.04, center: Any = (0, 0, 0), subdivisions: int = 4) -> Object:
    """Sphere of ``radius`` (default 4 cm), 20 * 4**subdivisions triangles."""
    r, c = positive("radius", radius), _center(center)  # every argument checked before any work
    v, f = icosphere(subdivisions)
    return Object(v * r + c, f)


def ellipsoid(radii: Any = (0.05, 0.04, 0.03), center: Any = (0, 0, 0), subdivisions: int = 4) -> Object:
    """Axis-aligned ellipsoid with semi-axes ``radii`` (default 5 x 4 x 3 cm)."""
    r, c = _sizes("radii", radii), _center(center)
    v, f = icosphere(subdivisions)
    return Object(v * r + c, f)


def blob(radius: float = 0.04, amplitude: float = 0.25, seed: int = 0, center: Any = (0, 0, 0),
         subdivisions: int = 4) -> Object:
    """A smooth, non-convex, star-shaped body: a sphere whose radius varies by a few low-order
    waves of relative ``amplitude`` (>= 0; random phases from ``seed``, a whole number >= 0)."""
    radius, amplitude = positive("radius", radius), positive("amplitude", amplitude, allow_zero=True)
    rng, c = np.random.default_rng(whole("seed", seed, 0)), _center(center)
    v, f = icosphere(subdivisions)
    scale = np.ones(len(v))
    for _ in range(4):
        k = rng.normal(size=3)
        k *= rng.uniform(2.0, 4.0) / float(_stable.norm(k))
        scale += amplitude / 4 * _stable.sin(_stable.matmul(v, k[:, None])[:, 0] + rng.uniform(0, 2 * np.pi))
    scale = np.maximum(scale, 0.4)
    return Object(v * (radius * scale)[:, None] + c, f)


def box(extents: Any = (0.06, 0.05, 0.04), center: Any = (0, 0, 0), divisions: int = 4) -> Object:
    """Axis-aligned box of full ``extents`` (default 6 x 5 x 4 cm), each face a grid of
    ``divisions`` x ``divisions`` squares (a whole number >= 1; at most MAX_TRIANGLES triangles)."""
    n = whole("divisions", divisions, 1)
    _triangles("the box", 12 * n * n)
    e, c = _sizes("extents", extents) / 2.0, _center(center)
    verts: dict[tuple[int, ...], int] = {}
    points: list[np.ndarray] = []
    faces: list[tuple[int, int, int]] = []

    def vid(ijk: tuple[int, ...]) -> int:
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
    return Object(np.array(points) + c, np.array(faces, dtype=np.int64))


def cylinder(radius: float = 0.035, height: float = 0.1, center: Any = (0, 0, 0), sections: int = 48,
             rings: int = 8) -> Object:
    """Cylinder along z of ``radius`` and ``height`` (default 3.5 x 10 cm), closed by flat caps:
    ``sections`` (>= 3) around, ``rings`` (>= 1) along z, at most MAX_TRIANGLES triangles."""
    radius, height = positive("radius", radius), positive("height", height)
    s, r = whole("sections", sections, 3), whole("rings", rings, 1)
    _triangles("the cylinder", 2 * s * (r + 1))
    origin = _center(center)
    ang = 2 * np.pi * np.arange(s) / s
    pts = [np.array([0.0, 0.0, -height / 2]), np.array([0.0, 0.0, height / 2])]
    for k in range(r + 1):
        z = -height / 2 + height * k / r
        pts += [np.array([radius * math.cos(a), radius * math.sin(a), z]) for a in ang]
    ring: Callable[[int, int], int] = lambda k, i: 2 + k * s + (i % s)  # noqa: E731
    faces = []
    for i in range(s):
        faces.append((0, ring(0, i + 1), ring(0, i)))
        faces.append((1, ring(r, i), ring(r, i + 1)))
        for k in range(r):
            faces += [(ring(k, i), ring(k, i + 1), ring(k + 1, i + 1)), (ring(k, i), ring(k + 1, i + 1), ring(k + 1, i))]
    return Object(np.array(pts) + origin, np.array(faces, dtype=np.int64))


def _star(v: np.ndarray, f: np.ndarray, rho: np.ndarray, center: Any) -> Object:
    """The star-shaped body whose surface is the unit sphere's point v moved to v * rho(v)."""
    return Object(v * rho[:, None] + _center(center), f)


def apple(radius: float = 0.04, center: Any = (0, 0, 0), subdivisions: int = 5) -> Object:
    """An apple: a sphere of ``radius`` (default 4 cm) widened at the equator (8.4 cm wide, 6.9 cm tall)
    with a stem dimple on top (+z) and a shallower calyx dimple below."""
    r, c = positive("radius", radius), _center(center)
    v, f = icosphere(subdivisions)
    theta = _stable.arccos(np.clip(v[:, 2], -1.0, 1.0))  # angle from +z
    rho = (1.0 - 0.30 * _stable.exp(-((theta / 0.38) ** 2)) - 0.15 * _stable.exp(-(((np.pi - theta) / 0.40) ** 2))
           + 0.05 * _stable.sin(theta) ** 2)
    rho = rho * r
    return _star(v, f, rho, c)


def curvy(size: float = 0.04, center: Any = (0, 0, 0), subdivisions: int = 5) -> Object:
    """The paper's "complex curvilinear body": a smooth, non-convex, bumpy body about
    ``2.1 * size`` long (x) and ``2 * size`` across (default 4 cm: about 9 x 8 x 8 cm), 20480 triangles.

    The unit sphere's point v = (x, y, z) moves to ``v * rho(v) * size``, then x is stretched by 1.2::

        rho = 1 + 0.20 sin(3.0x+0.7) cos(2.5y-0.3) + 0.12 sin(4.0z+1.2) cos(2.0x-0.5)
                + 0.10 cos(3.5y+0.9) sin(2.5z) - 0.10 exp(-((x-0.1)/0.3)^2)

    (The benchmark binary ``hugger_bench`` builds the same body.)
    """
    scale, c = positive("size", size), _center(center)
    v, f = icosphere(subdivisions)
    x, y, z = v.T
    sin, cos, exp = _stable.sin, _stable.cos, _stable.exp  # the C library's, as hugger_bench's
    rho = (1.0 + 0.20 * sin(3.0 * x + 0.7) * cos(2.5 * y - 0.3) + 0.12 * sin(4.0 * z + 1.2) * cos(2.0 * x - 0.5)
           + 0.10 * cos(3.5 * y + 0.9) * sin(2.5 * z) - 0.10 * exp(-(((x - 0.1) / 0.3) ** 2)))
    p = v * (rho * scale)[:, None]
    p[:, 0] *= 1.2
    return Object(p + c, f)


def torus(major_radius: float = 0.04, minor_radius: float = 0.015, center: Any = (0, 0, 0), sections: int = 96,
          rings: int = 32) -> Object:
    """A ring about z: tube radius ``minor_radius`` (default 1.5 cm) around a circle of ``major_radius``
    (default 4 cm), so 11 x 11 x 3 cm. Its centre is not inside it: the natural target is in the tube,
    at (major_radius, 0, 0) from the centre. ``sections`` (>= 3) around z, ``rings`` (>= 3) around
    the tube, at most MAX_TRIANGLES triangles."""
    major_radius, minor_radius = positive("major_radius", major_radius), positive("minor_radius", minor_radius)
    if not minor_radius < major_radius:
        raise ValueError(f"torus needs minor_radius < major_radius, got {minor_radius!r} and {major_radius!r}")
    s, r = whole("sections", sections, 3), whole("rings", rings, 3)
    _triangles("the torus", 2 * s * r)
    origin = _center(center)
    u = 2 * np.pi * np.arange(s) / s
    w = 2 * np.pi * np.arange(r) / r
    uu, ww = np.meshgrid(u, w, indexing="ij")
    rad = major_radius + minor_radius * _stable.cos(ww)
    pts = np.stack([rad * _stable.cos(uu), rad * _stable.sin(uu), minor_radius * _stable.sin(ww)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(s), np.arange(r), indexing="ij")
    a, b = i * r + j, ((i + 1) % s) * r + j
    c, d = ((i + 1) % s) * r + (j + 1) % r, i * r + (j + 1) % r
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return Object(pts + origin, faces.astype(np.int64))


@dataclass(frozen=True)
class Builtin:
    """A built-in object: how to make it, its size, the natural target T and approach direction."""

    name: str
    make: Callable[[], Object]
    size: str
    description: str
    target: tuple[float, float, float] = (0.0, 0.0, 0.0)
    approach: tuple[float, float, float] = (0.0, 0.0, 1.0)  #: direction from T to the default start


BUILTINS: dict[str, Builtin] = {b.name: b for b in (
    Builtin("sphere", sphere, "r 4 cm", "sphere, 5120 triangles"),
    Builtin("apple", apple, "8.4 x 8.4 x 6.9 cm", "apple with stem and calyx dimples, 20480 triangles"),
    Builtin("ellipsoid", ellipsoid, "10 x 8 x 6 cm", "ellipsoid with semi-axes 5, 4, 3 cm, 5120 triangles"),
    Builtin("cylinder", cylinder, "r 3.5 cm, h 10 cm", "cylinder along z with flat caps", approach=(1.0, 0.0, 0.0)),
    Builtin("box", box, "6 x 5 x 4 cm", "box, each face a 4 x 4 grid"),
    Builtin("torus", torus, "11 x 11 x 3 cm", "ring (tube r 1.5 cm on a 4 cm circle); T inside the tube",
            target=(0.04, 0.0, 0.0), approach=(1.0, 0.0, 0.0)),
    Builtin("curvy", curvy, "8.7 x 8.1 x 8.1 cm", "smooth non-convex bumpy body, the paper's example, 20480 triangles"),
)}


def names() -> list[str]:
    """Names of the built-in objects."""
    return list(BUILTINS)


def get(name: str) -> Object:
    """The built-in object ``name`` (see ``BUILTINS``)."""
    try:
        return BUILTINS[name].make()
    except KeyError:
        raise ValueError(f"unknown built-in object {name!r}; choose from {', '.join(BUILTINS)}") from None


MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf")


def load(path: str | os.PathLike[str], scale: float = 1.0) -> Object:
    """Read a mesh file (any format trimesh reads: STL, OBJ, PLY, OFF, GLB) as an Object.

    ``scale`` multiplies the coordinates (0.001 for a file in millimetres). See :func:`load_mesh`
    for what is repaired; a mesh that cannot be repaired safely raises ``ValueError``.
    """
    return load_mesh(path, scale)[0]


#: The smallest mesh read (m across, after scaling): coincident vertices are merged at trimesh's
#: tolerance (1e-8 m), which would collapse a smaller one. (A plausible object is 1 mm or more.)
_SMALLEST_READ = 1e-6


def load_mesh(path: str | os.PathLike[str], scale: float = 1.0) -> tuple[Object, list[str]]:
    """Like :func:`load`, and also say what was repaired.

    Safe repairs, which change no enclosed volume: coincident vertices merged; faces that
    repeat a vertex dropped; a face repeated with the same orientation kept once; a face
    repeated with both orientations (a zero-volume fin) dropped; consistent but inward
    orientation flipped; a closed, manifold mesh with inconsistent winding re-wound. A mesh
    with holes or non-manifold edges that remain is refused: guessing its surface could make
    the planner grasp something that is not there.
    """
    from ._signals import kept

    try:
        with kept():  # (trimesh swallows an interrupt while it imports)
            import trimesh
    except ImportError:
        raise ImportError("reading mesh files needs trimesh: pip install 'hugger[mesh]'") from None
    path = os.fspath(path)
    scale = positive("scale", scale)
    if os.path.isdir(path):
        raise IsADirectoryError(f"{path} is a directory, not a mesh file")
    if os.path.exists(path) and not os.path.isfile(path):
        raise ValueError(f"{path} is not a regular file (a device or pipe), not a mesh file")
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such mesh file: {path}")
    if not os.path.splitext(path)[1]:
        raise ValueError(f"{path} has no extension: name it by its format (.stl, .obj, .ply, .off, .glb, ...)")
    try:
        with kept():
            mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise ValueError(f"cannot read mesh file {path!r}: {exc}") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ValueError(f"{path!r} holds no triangles")
    vertices = np.asarray(mesh.vertices, dtype=np.float64) * scale
    faces = np.asarray(mesh.faces, dtype=np.int64)
    size = float(np.ptp(vertices, axis=0).max()) if len(vertices) else 0.0
    if np.isfinite(size) and size < _SMALLEST_READ:
        raise ValueError(f"{os.path.basename(path)} is {size:g} m across (scale {scale:g}): too small to read, its "
                         f"vertices would merge; hugger works in metres")
    with np.errstate(divide="ignore", invalid="ignore"), kept():  # trimesh's mass properties of a flat part
        vertices, faces, repairs = _repair(vertices, faces)
    try:
        return Object(vertices, faces), repairs
    except ValueError as exc:
        raise ValueError(f"{os.path.basename(path)}: {exc}; it cannot be repaired safely") from None


def _repair(v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str]]:
    import trimesh

    repairs: list[str] = []
    if not np.all(np.isfinite(v)) or (v.size and np.abs(v).max() > MAX_COORDINATE):
        return v, f, repairs  # Object says which vertex (trimesh's merge would lose them)
    if f.size and (f.min() < 0 or f.max() >= len(v)):
        return v, f, repairs  # Object says which face (trimesh would fail on the index)
    mesh = trimesh.Trimesh(v, f, process=False)
    mesh.merge_vertices()
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces, dtype=np.int64)
    # merging coincident vertices is how an STL (one vertex triple per face) is read, not a
    # repair: it is not reported
    repeat = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
    if repeat.any():
        f = f[~repeat]
        repairs.append(f"dropped {int(repeat.sum())} faces that repeat a vertex")
    key = np.sort(f, axis=1)
    _, first, inverse, counts = np.unique(key, axis=0, return_index=True, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    if np.any(counts > 1):
        # Orientation of each face relative to its sorted key: even or odd permutation.
        rolled = np.array([np.roll(row, -int(np.argmin(row))) for row in f])
        parity = rolled[:, 1] < rolled[:, 2]
        keep = np.ones(len(f), dtype=bool)
        fins = same = 0
        for g in np.flatnonzero(counts > 1):
            members = np.flatnonzero(inverse == g)
            up, down = members[parity[members]], members[~parity[members]]
            keep[members] = False
            if len(up) == len(down):
                fins += len(members)
            else:  # keep one face of the majority orientation, minus the cancelling pairs
                survivor = up[0] if len(up) > len(down) else down[0]
                keep[survivor] = True
                same += len(members) - 1
        f = f[keep]
        if fins:
            repairs.append(f"dropped {fins} faces forming zero-volume fins (a face and its reverse)")
        if same:
            repairs.append(f"dropped {same} duplicate faces")
    mesh = trimesh.Trimesh(v, f, process=False)
    if mesh.is_watertight and not mesh.is_winding_consistent:
        trimesh.repair.fix_winding(mesh)  # type: ignore[no-untyped-call]
        if mesh.is_winding_consistent:
            f = np.asarray(mesh.faces, dtype=np.int64)
            repairs.append("re-wound faces to a consistent orientation")
    if mesh.is_watertight and mesh.is_winding_consistent and mesh.volume < 0:
        f = f[:, ::-1].copy()
        repairs.append("flipped inward-facing orientation")
    used = np.unique(f)
    if len(used) < len(v):
        remap = np.full(len(v), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        v, f = v[used], remap[f]
    return v, f, repairs
