"""Skins: the planner's only source of facts about the object (see docs/skins.md).

A skin answers two primitive queries, in metres, in the world frame:

- ``capsule(a, b, radius, cap) -> Touch``: the gap between the capsule of axis ``[a, b]`` (3,)
  and ``radius`` and the object, with the nearest points and the outward normal;
- ``palm(pose, radius, thickness, cap) -> float``: the gap between the palm disk and the object.

Gaps are signed (negative when the part penetrates the object) and must be exact whenever they
are at most ``cap``; above ``cap`` any value above ``cap`` (``inf`` included) may be returned.

Skins here:

- :class:`MeshSkin` the simulated mesh world (C++, the reference), what ``Planner`` builds from
  an :class:`hugger.Object`;
- :class:`SphereSkin`, :class:`BoxSkin`, :class:`SpheresSkin` analytic shapes given by formulas
  (no mesh), written in Python as examples;
- :class:`SensorModel` wraps any skin with a sensing range, Gaussian noise and taxels.

``hugger.physics.MujocoSkin`` senses through MuJoCo's collision on a simulated scene.
"""
from __future__ import annotations

from .._core import Sensing, Touch
from .analytic import BoxSkin, SphereSkin, SpheresSkin
from .mesh import MeshSkin
from .sensor import SensorModel

__all__ = ["BoxSkin", "MeshSkin", "SensorModel", "Sensing", "SphereSkin", "SpheresSkin", "Touch"]
