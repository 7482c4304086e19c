"""The simulated mesh world as a skin object."""
from __future__ import annotations

from typing import Any

from .. import _core


def MeshSkin(obj: Any) -> _core.SimulatedWorld:  # noqa: N802 (a factory named like the class it returns)
    """The reference skin of a :class:`hugger.Object`: exact 3D queries on a BVH of its mesh
    (the skin ``Planner`` builds when given the object itself). Callable from Python, so that a
    Python skin (a sensor model, say) can wrap it. Its ``object`` is ``obj``: a plan made with it
    (or with a :class:`SensorModel` of it) records that object."""
    from ..world import Object

    if not isinstance(obj, Object):
        raise ValueError(f"obj must be a hugger.Object, got {type(obj).__name__}")
    skin = _core.SimulatedWorld(obj._core)
    setattr(skin, "object", obj)  # (an attribute of this skin only: the class declares none)
    return skin


def recorded_object(skin: Any) -> Any:
    """The :class:`hugger.Object` a plan made with ``skin`` records when no ``record_object`` is
    given: that of a :func:`MeshSkin`, or of a :class:`SensorModel` of an Object or of such a
    skin; None for any other skin (its shape is its own)."""
    from ..world import Object
    from .sensor import SensorModel

    obj = getattr(skin, "object", None) if isinstance(skin, (SensorModel, _core.SimulatedWorld)) else None
    return obj if isinstance(obj, Object) else None
