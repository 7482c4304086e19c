"""Shared by the parts of :mod:`hugger.physics`: the lazy imports of MuJoCo and CoACD, the checks of
a trajectory argument and its configuration index, and numbers written into MJCF text."""
from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..trajectory import Trajectory, configuration_index


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
    """Configuration ``k`` of ``traj`` as an index (trajectory.configuration_index's rule), every
    refusal a ValueError (the physics API's, out of range included)."""
    try:
        return configuration_index(len(traj), k)
    except IndexError as exc:
        raise ValueError(str(exc)) from None


def _resets(mujoco: Any, data: Any) -> int:
    """How often MuJoCo has reset ``data`` since it was made, its accelerations having blown up (it
    warns, then starts again from the model's initial state: finite figures that mean nothing)."""
    return int(data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number)
