"""The simulated mesh world as a skin object."""
from __future__ import annotations

from typing import Any

from .. import _core


def MeshSkin(obj: Any) -> _core.SimulatedWorld:  # noqa: N802 (a factory named like the class it returns)
    """The reference skin of a :class:`hugger.Object`: exact 3D queries on a BVH of its mesh
    (the skin ``Planner`` builds when given the object itself). Callable from Python, so that a
    Python skin (a sensor model, say) can wrap it."""
    from ..world import Object

    if not isinstance(obj, Object):
        raise ValueError(f"obj must be a hugger.Object, got {type(obj).__name__}")
    return _core.SimulatedWorld(obj._core)
