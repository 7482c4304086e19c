"""Shared by the parts of :mod:`hugger.physics`: the lazy imports of MuJoCo and CoACD, the checks of
a trajectory argument and its configuration index, and numbers written into MJCF text."""
from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..trajectory import Trajectory


def _mujoco(user: str = "the physics check") -> Any:
    """The mujoco module; ``ImportError`` saying that ``user`` needs it, and how to install it, when missing."""
    try:
        import mujoco
    except ImportError as exc:
        raise ImportError(f"{user} needs MuJoCo: pip install 'hugger[physics]'") from exc
    return mujoco


def _coacd() -> Any:
    try:
        import coacd
    except ImportError as exc:
        raise ImportError("convex decomposition needs CoACD: pip install 'hugger[physics]' "
                          "(or pass decompose=False to use the object's convex hull)") from exc
    return coacd


def _floats(a: Any, fmt: str = "{:.17g}") -> str:
    return " ".join(fmt.format(float(x)) for x in np.asarray(a, dtype=np.float64).ravel())


def _trajectory(traj: Any, needs_object: bool = False) -> Trajectory:
    if isinstance(traj, (str, os.PathLike)):
        out = Trajectory.load(traj)
    elif isinstance(traj, Trajectory):
        out = traj
    else:
        raise ValueError(f"traj must be a hugger.Trajectory or a path to a trajectory file, got {type(traj).__name__}")
    if needs_object:
        out.object()  # an object-free plan is refused here, saying why
    return out


def _index(traj: Trajectory, k: Any) -> int:
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
        raise ValueError(f"k must be a whole number, got {k!r}")
    n = len(traj)
    if not -n <= int(k) < n:
        raise ValueError(f"k = {k} is out of range for a trajectory of {n} configurations")
    return int(k) % n
