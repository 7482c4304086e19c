"""Hugger: sensor-based enveloping ("hugging") grasp planning for multi-finger hands.

After D. Reznik and V. Lumelsky, "Multi-Finger Hugging: A Robust Approach to
Sensor-Based Grasp Planning", ICRA 1994. The engine is C++17 (``hugger._core``);
this package holds the Python API::

    import hugger
    hand = hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004,
                       palm_radius=0.03, palm_thickness=0.01)
    obj = hugger.objects.sphere(radius=0.04)
    planner = hugger.Planner(hand, obj, target=[0, 0, 0], palm_pose=hugger.look_at([0.2, 0, 0], [0, 0, 0]))
    traj = planner.plan()
    traj.save("plan.npz")
"""
from typing import Any as _Any

from . import hands, objects, scenarios, skins
from .batch import CaseError, PlanManyError, plan_many
from .hand import Hand
from ._types import CONTACT, DONE, FROZEN, VERSION, Configuration, TipState
from .planner import Planner, look_at, plan
from .search import Candidate, SearchResult, approach_directions, search
from .trajectory import FORMAT_VERSION, Trajectory
from .world import Object
from .skins import Sensing, Touch

__version__ = VERSION

_LAZY = ("analysis", "viz", "physics", "cli", "viewer", "dataset", "baselines")


def __getattr__(name: str) -> _Any:
    """Submodules with optional dependencies load on first use: ``hugger.analysis``, ``hugger.viz``,
    ``hugger.physics``, ``hugger.dataset`` (``import hugger`` itself needs only numpy);
    ``hugger.Dataset`` is ``hugger.dataset.Dataset``."""
    if name == "Dataset":
        from .dataset import Dataset

        return Dataset
    if name in _LAZY:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """What the package holds, the lazily loaded submodules and ``Dataset`` included (for tab
    completion), without loading them."""
    return sorted(set(globals()) | set(_LAZY) | {"Dataset"})


__all__ = [
    "CONTACT",
    "Candidate",
    "CaseError",
    "DONE",
    "Dataset",
    "FORMAT_VERSION",
    "FROZEN",
    "Configuration",
    "Hand",
    "Object",
    "PlanManyError",
    "Planner",
    "SearchResult",
    "TipState",
    "Sensing",
    "Touch",
    "Trajectory",
    "approach_directions",
    "hands",
    "look_at",
    "objects",
    "plan",
    "plan_many",
    "scenarios",
    "skins",
    "search",
    "__version__",
]
