"""Mass properties of a closed mesh, and the volume of its convex hull as MuJoCo computes it."""
from __future__ import annotations

from typing import Any

import numpy as np

from ._common import _floats, _mujoco


def mass_properties(vertices: Any, faces: Any) -> tuple[float, np.ndarray, np.ndarray]:
    """Volume (m³), centre of volume (3,) and inertia tensor (3, 3) per unit density (m⁵) about
    that centre, in the mesh's frame, of a closed mesh with outward faces."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3 or len(f) == 0:
        raise ValueError("vertices must be (V, 3) and faces (F, 3), not empty")
    ref = v.mean(axis=0)
    tri = v[f] - ref  # tetrahedra (ref, a, b, c)
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    vol6 = np.einsum("ij,ij->i", a, np.cross(b, c))
    volume = float(vol6.sum() / 6.0)
    if not volume > 0:
        raise ValueError(f"the mesh encloses no positive volume ({volume:g} m^3): not closed or inside-out")
    s = a + b + c
    centre = (vol6[:, None] * s).sum(axis=0) / 24.0 / volume
    # second moment of each tetrahedron about ref: V/20 (sum p p^T + s s^T)
    second = (np.einsum("t,ti,tj->ij", vol6 / 6.0, a, a) + np.einsum("t,ti,tj->ij", vol6 / 6.0, b, b)
              + np.einsum("t,ti,tj->ij", vol6 / 6.0, c, c) + np.einsum("t,ti,tj->ij", vol6 / 6.0, s, s)) / 20.0
    second -= volume * np.outer(centre, centre)
    inertia = np.trace(second) * np.eye(3) - second
    return volume, centre + ref, inertia


def hull_volume(vertices: Any) -> float:
    """Volume (m³) of the convex hull of ``vertices`` (V, 3), as MuJoCo computes it."""
    mujoco = _mujoco()
    v = np.asarray(vertices, dtype=np.float64)
    shift = v.mean(axis=0)
    # MuJoCo refuses a free body whose mass or any principal inertia is below its mjMINVAL (1e-15):
    # at unit density, a hull under about 1 cm across, or a needle. Such a hull is weighed again
    # at the density that gives its bounding box a mass of 1 kg (the others at unit density).
    def weighed(density: float) -> float:
        xml = (f'<mujoco><asset><mesh name="m" inertia="convex" vertex="{_floats(v - shift, "{:.9g}")}"/></asset>'
               f'<worldbody><body><freejoint/><geom type="mesh" mesh="m" density="{density!r}"/></body>'
               '</worldbody></mujoco>')
        return float(mujoco.MjModel.from_xml_string(xml).body_mass[1]) / density

    try:
        return weighed(1.0)
    except ValueError as exc:
        box = float(np.prod(np.ptp(v, axis=0)))
        if "mjMINVAL" not in str(exc) or not box > 0.0:
            raise
        return weighed(1.0 / box)
