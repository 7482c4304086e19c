"""The object O: a closed triangle mesh, validated, with the queries the simulated world uses."""
from __future__ import annotations

from typing import Any

import numpy as np

from . import _core


class Object:
    """A rigid, closed, consistently oriented (outward normals) triangle mesh in the world frame.

    ``vertices`` is (V, 3) float in metres, ``faces`` (F, 3) int. Raises ``ValueError`` naming
    what is wrong: empty, non-finite, indices out of range, degenerate faces, not closed, not
    consistently oriented, or inside-out.
    """

    def __init__(self, vertices: Any, faces: Any) -> None:
        try:
            v = np.array(vertices, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError("vertices must be a numeric (V, 3) array") from None
        f_in = np.asarray(faces)
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices must be (V, 3), got shape {v.shape}")
        if f_in.ndim != 2 or f_in.shape[1] != 3:
            raise ValueError(f"faces must be (F, 3), got shape {f_in.shape}")
        if f_in.size and f_in.dtype.kind not in "iu":
            if f_in.dtype.kind != "f" or not np.all(np.isfinite(f_in)) or np.any(f_in != np.round(f_in)):
                raise ValueError("faces must hold whole-number vertex indices")
        f = f_in.astype(np.int64)
        if not np.all(np.isfinite(v)):
            bad = int(np.argwhere(~np.isfinite(v).all(axis=1))[0, 0])
            raise ValueError(f"object vertex {bad} is not finite: {v[bad].tolist()}")
        self._core = _core.Object(v, f)
        v.setflags(write=False)
        f.setflags(write=False)
        self._vertices, self._faces = v, f

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
        tri = self._vertices[self._faces]
        vol = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
        return (vol[:, None] * tri.sum(axis=1) / 4.0).sum(axis=0) / vol.sum()

    def inside(self, points: Any) -> np.ndarray:
        """Bool (n,): strictly inside O, for points (n, 3) or one point (3,)."""
        p = np.asarray(points, dtype=np.float64)
        return self._core.inside(p.reshape(-1, 3)).reshape(p.shape[:-1])

    def signed_distance(self, points: Any) -> np.ndarray:
        """Signed distance to the surface (negative inside) for points (n, 3) or (3,)."""
        p = np.asarray(points, dtype=np.float64)
        return self._core.signed_distance(p.reshape(-1, 3)).reshape(p.shape[:-1])

    def closest(self, points: Any) -> dict[str, np.ndarray]:
        """For points (n, 3): ``distance`` (n,) signed (negative inside), closest surface ``point``
        (n, 3), outward unit ``normal`` (n, 3) of its triangle, and the ``triangle`` index (n,)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return self._core.closest(p)

    def segment_distance(self, a: Any, b: Any) -> np.ndarray:
        """Signed distance (n,) of segments [a_i, b_i] to O (<= 0 when crossing the surface)."""
        return self._core.segment_distance(np.asarray(a, dtype=np.float64).reshape(-1, 3),
                                           np.asarray(b, dtype=np.float64).reshape(-1, 3))

    def section(self, origin: Any, u: Any, v: Any) -> list[np.ndarray]:
        """Planar section by origin + a u + b v (u, v orthonormal): closed loops (k, 2) in (a, b)."""
        as3 = lambda x: np.asarray(x, dtype=np.float64)  # noqa: E731
        return self._core.section(as3(origin), as3(u), as3(v))

    def __repr__(self) -> str:
        ext = np.ptp(self.bounds, axis=0) * 1000
        return f"Object({len(self._faces)} triangles, {ext[0]:.0f} x {ext[1]:.0f} x {ext[2]:.0f} mm)"
