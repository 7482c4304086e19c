"""The object O: a closed triangle mesh, validated, with the queries the simulated world uses."""
from __future__ import annotations

import math
import warnings
from typing import Any, cast

import numpy as np

from . import _core
from ._checks import real_array, shown
from .hand import implausible_size

#: Vertex coordinates beyond this (m) are refused: no grasp scene spans a thousand kilometres, and
#: the engine's tolerances are absolute (1e-7 m .. 1e-4 m), which float64 resolves only while
#: coordinates stay well below 1e6 m (there the spacing of doubles is already 1e-10 m). Move a
#: georeferenced mesh to a local origin first.
MAX_COORDINATE: float = _core.MAX_COORDINATE  # the engine's kMaxCoordinate, also the bound of skin queries


def _face_indices(faces: Any, nv: int) -> np.ndarray:
    """Faces as an (F, 3) int64 array of indices into nv vertices, checked before the cast so that
    no index wraps around (uint64 or float input)."""
    if faces is None:
        raise ValueError("faces must be an (F, 3) array of vertex indices, got None")
    try:
        a = np.asarray(faces)
    except (TypeError, ValueError, OverflowError, RecursionError):
        raise ValueError("faces must be an (F, 3) array of vertex indices") from None
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"faces must be (F, 3), got shape {a.shape}")
    if a.dtype.kind == "O":
        try:
            a = a.astype(np.float64)
        except (TypeError, ValueError, OverflowError):
            raise ValueError("faces must hold whole-number vertex indices, got Python objects") from None
    if a.dtype.kind == "f":
        if not np.all(np.isfinite(a)) or np.any(a != np.round(a)):
            raise ValueError("faces must hold whole-number vertex indices")
    elif a.dtype.kind not in "iu":
        raise ValueError(f"faces must hold whole-number vertex indices, got dtype {a.dtype}")
    if a.size and nv:  # an empty mesh is reported as such by the engine
        bad = (a < 0) | (a >= nv)
        if bad.any():
            i, k = np.argwhere(bad)[0]
            x = a[i, k].item()
            raise ValueError(f"object face {i} indexes vertex {int(x) if isinstance(x, float) else x}, "
                             f"outside 0..{nv - 1}")
    return a.astype(np.int64)


class Object:
    """A rigid, closed, consistently oriented (outward normals) triangle mesh in the world frame.

    ``vertices`` is (V, 3) real numbers in metres (|coordinate| <= :data:`MAX_COORDINATE`),
    ``faces`` (F, 3) whole-number indices. Raises ``ValueError`` naming what is wrong: empty,
    non-finite, indices out of range, degenerate (zero-area) or duplicate faces, not closed,
    not manifold, not consistently oriented, or inside-out. An object whose bounding box is
    larger than 3 m or smaller than 1 mm (:data:`hugger.hand.PLAUSIBLE_SIZE`) is accepted with
    a ``UserWarning``: it was most likely given in millimetres (``warn_size=False`` silences it,
    for an object already accepted once, such as the one a trajectory file holds).
    """

    def __init__(self, vertices: Any, faces: Any, *, warn_size: bool = True) -> None:
        v = np.array(real_array("vertices", vertices), dtype=np.float64)  # a private copy
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices must be (V, 3), got shape {v.shape}")
        f = _face_indices(faces, len(v))
        if not np.all(np.isfinite(v)):
            bad = int(np.argwhere(~np.isfinite(v).all(axis=1))[0, 0])
            raise ValueError(f"object vertex {bad} is not finite: {v[bad].tolist()}")
        if v.size and np.abs(v).max() > MAX_COORDINATE:
            bad = int(np.argmax(np.abs(v).max(axis=1)))
            raise ValueError(f"object vertex {bad} = {v[bad].tolist()} lies beyond {MAX_COORDINATE:g} m of the "
                             f"origin: coordinates are in metres (move the mesh near the origin)")
        self._core = _core.Object(v, f)  # the engine checks the surface (closed, manifold, ...)
        v.setflags(write=False)
        f.setflags(write=False)
        self._vertices, self._faces = v, f
        message = self.size_warning if warn_size else None
        if message:
            warnings.warn(message, UserWarning, stacklevel=2)

    @property
    def size_warning(self) -> str | None:
        """The warning of an object whose size is implausible for a grasp (its largest extent
        outside :data:`hugger.hand.PLAUSIBLE_SIZE`: millimetres read as metres), or None."""
        return implausible_size("the object", float(np.ptp(self.bounds, axis=0).max()))

    @property
    def vertices(self) -> np.ndarray:
        return self._vertices

    @property
    def faces(self) -> np.ndarray:
        return self._faces

    @property
    def volume(self) -> float:
        """Enclosed volume (m^3)."""
        return float(self._core.volume)

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3): min and max corners."""
        return self._core.bounds

    @property
    def centroid(self) -> np.ndarray:
        """Centre of the enclosed volume (uniform density)."""
        ref = self._vertices.min(axis=0) / 2 + self._vertices.max(axis=0) / 2  # about the box centre: no cancellation
        tri = self._vertices[self._faces] - ref
        vol = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
        return cast(np.ndarray, ref + (vol[:, None] * tri.sum(axis=1) / 4.0).sum(axis=0) / vol.sum())

    def inside(self, points: Any) -> np.ndarray:
        """Bool (n,): strictly inside O, for points (n, 3) or one point (3,); ``ValueError`` for a
        point that is not finite."""
        p = real_array("points", points)
        return self._core.inside(p.reshape(-1, 3)).reshape(p.shape[:-1])

    def signed_distance(self, points: Any) -> np.ndarray:
        """Signed distance to the surface (negative inside) for points (n, 3) or (3,); ``ValueError``
        for a point that is not finite."""
        p = real_array("points", points)
        return self._core.signed_distance(p.reshape(-1, 3)).reshape(p.shape[:-1])

    def closest(self, points: Any, max_distance: float = math.inf) -> dict[str, np.ndarray]:
        """For points (n, 3): ``distance`` (n,) signed (negative inside), closest surface ``point``
        (n, 3), outward unit ``normal`` (n, 3) of its triangle, and the ``triangle`` index (n,).
        Points farther than ``max_distance`` (m) from the surface may be skipped, which is faster:
        their distance is then +inf or -inf (the sign still says outside or inside), point and
        normal NaN, triangle -1. ``ValueError`` for a point that is not finite."""
        p = real_array("points", points).reshape(-1, 3)
        try:
            bound = float(max_distance)
        except (TypeError, ValueError):
            raise ValueError(f"max_distance must be a number >= 0 (inf: no bound), got {shown(max_distance)}") from None
        return self._core.closest(p, bound)  # the core checks the value

    def segment_distance(self, a: Any, b: Any) -> np.ndarray:
        """Signed distance (n,) of segments [a_i, b_i] to O (<= 0 when crossing the surface);
        ``ValueError`` for an end that is not finite."""
        return self._core.segment_distance(real_array("a", a).reshape(-1, 3), real_array("b", b).reshape(-1, 3))

    def section(self, origin: Any, u: Any, v: Any) -> list[np.ndarray]:
        """Planar section by origin + a u + b v (u, v orthonormal): closed loops (k, 2) in (a, b)."""
        return self._core.section(real_array("origin", origin), real_array("u", u), real_array("v", v))

    def __repr__(self) -> str:
        ext = np.ptp(self.bounds, axis=0) * 1000
        return f"Object({len(self._faces)} triangles, {ext[0]:.0f} x {ext[1]:.0f} x {ext[2]:.0f} mm)"
