"""Ready-made planning cases: an object, a target point T inside it, and a safe start pose.

``default_case("curvy", hand)`` or ``default_case("mug.stl", hand, scale=0.001)`` gives what the
``hugger`` command plans by default: T is the built-in's natural target (for a mesh file: its
volume centroid, or the deepest interior point when the centroid lies outside or near the
surface), and the palm starts on the approach direction (+z for mesh files) at
:func:`safe_distance`, facing T.
"""
from __future__ import annotations

import math
import os
import threading
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _stable, objects
from ._checks import number, positive, real_array, shown
from .hand import Hand
from .planner import look_at
from .world import Object


@dataclass(frozen=True)
class Case:
    """One planning problem: ``Planner(hand, case.obj, case.target, case.palm_pose)``."""

    name: str
    obj: Object
    target: np.ndarray  #: T (3,), inside obj
    palm_pose: np.ndarray  #: (4, 4) start pose, clear of obj
    repairs: list[str] = field(default_factory=list)  #: what loading a mesh file repaired
    hand: Hand | None = None  #: the hand the start pose was made for (what :func:`hugger.plan_many` plans with)


def safe_distance(obj: Object, hand: Hand, target: Any, margin: float = 0.005) -> float:
    """A palm distance from T at which the hand, in any orientation, clears the object by
    ``margin``: the object's radius about T plus the hand's radius about the palm centre."""
    t = real_array("target", target).reshape(3)
    body = _stable.farthest(obj.vertices, t)
    hand_radius: float = max(math.hypot(hand.palm_radius, hand.reach) + hand.link_radius,
                              math.hypot(hand.palm_radius, hand.palm_thickness))
    if hand.general:  # roots anywhere on the palm, fingers at rest in any pose
        hand_radius = max(hand_radius, float(hand._core.extended_radius) + hand.link_radius)
    return body + hand_radius + margin


def _turn(turn_deg: Any) -> float:
    """A start's turn in degrees: a number from -180 to 180 (the one rule of start_pose and default_case)."""
    x = number("turn_deg (--turn)", turn_deg)
    if not (math.isfinite(x) and -180.0 <= x <= 180.0):
        raise ValueError(f"turn_deg (--turn) must be within [-180, 180] degrees, got {shown(turn_deg)}")
    return x


def start_pose(obj: Object, hand: Hand, target: Any, direction: Any = (0.0, 0.0, 1.0), turn_deg: float = 0.0,
               distance: float | None = None) -> np.ndarray:
    """The palm at ``distance`` (default :func:`safe_distance`) from T along ``direction``, facing T,
    then turned by ``turn_deg`` (-180 to 180) about its own y axis so that Phase 1 has work to do."""
    turn_deg = _turn(turn_deg)
    t = real_array("target", target).reshape(3)
    d = _unit("direction", direction)
    dist = safe_distance(obj, hand, t) if distance is None else positive("distance", distance)
    pose = look_at(t + dist * d, t)
    if turn_deg:
        c, s = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
        pose[:3, :3] = _stable.matmul(pose[:3, :3], np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]))
    return pose


def interior_target(obj: Object) -> np.ndarray:
    """A natural T for an arbitrary mesh: its volume centroid when that is inside and at least
    half as deep as the deepest point found on a 24^3 grid; otherwise that deepest point."""
    lo, hi = obj.bounds
    axes = [np.linspace(lo[i], hi[i], 26)[1:-1] for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    depth = -obj.signed_distance(grid)
    best = grid[int(np.argmax(depth))]
    c = obj.centroid
    c_depth = -float(obj.signed_distance(c[None])[0])
    return c if c_depth > 0 and c_depth >= 0.5 * float(depth.max()) else best


#: Mesh files already read, by (absolute path, size, modification time, scale): an Object is
#: immutable, so cases built from one file share it (building 180 cases reads each file once).
_MESH_CACHE: dict[tuple[str, int, int, float], tuple[Object, list[str]]] = {}
_MESH_CACHE_SIZE = 64
_MESH_LOCK = threading.Lock()
#: The built-in objects already made (each is made once per process).
_BUILTIN_CACHE: dict[str, Object] = {}


def _load_mesh_cached(path: str, scale: float) -> tuple[Object, list[str]]:
    try:
        st = os.stat(path)
    except OSError:
        return objects.load_mesh(path, scale)  # says what is wrong
    key = (os.path.abspath(path), st.st_size, st.st_mtime_ns, scale)
    with _MESH_LOCK:
        hit = _MESH_CACHE.get(key)
    if hit is not None:
        return hit[0], list(hit[1])
    obj, repairs = objects.load_mesh(path, scale)
    with _MESH_LOCK:
        if len(_MESH_CACHE) >= _MESH_CACHE_SIZE:
            _MESH_CACHE.pop(next(iter(_MESH_CACHE)))
        _MESH_CACHE[key] = (obj, list(repairs))
    return obj, repairs


def load_object(spec: str | os.PathLike[str], scale: float = 1.0) -> tuple[str, Object, list[str]]:
    """A built-in name or a mesh file path -> (name, Object, repairs).

    ``scale`` multiplies a mesh file's coordinates; built-ins are sized in metres and refuse any
    scale other than 1 (``ValueError``). A mesh file is read once per (path, size, modification
    time, scale), and a built-in made once, the Object shared by later calls."""
    s = os.fspath(spec)
    scale = positive("scale", scale)
    if s in objects.BUILTINS:
        if scale != 1.0:
            raise ValueError(f"scale applies to mesh files only; {s!r} is a built-in object, sized in metres "
                             f"(got scale {scale:g})")
        with _MESH_LOCK:
            if s not in _BUILTIN_CACHE:
                _BUILTIN_CACHE[s] = objects.get(s)
            return s, _BUILTIN_CACHE[s], []
    if os.path.splitext(s)[1].lower() in objects.MESH_SUFFIXES or os.path.exists(s):
        obj, repairs = _load_mesh_cached(s, scale)
        return os.path.basename(s), obj, repairs
    raise ValueError(f"{s!r} is neither a built-in object ({', '.join(objects.BUILTINS)}) nor a mesh file")


def default_case(spec: str | os.PathLike[str], hand: Hand | None = None, scale: float = 1.0, target: Any = None,
                 start: Any = None, normal: Any = None, turn_deg: float = 0.0) -> Case:
    """The case the ``hugger plan`` command solves for ``spec`` (built-in name or mesh file), with
    ``hand`` (default ``Hand()``, the 5 x 5 hand) recorded in the case so that
    ``plan_many([default_case(...), ...])`` plans it as the command would.

    ``target`` overrides T; ``start`` the palm centre; ``normal`` the palm normal (default: towards T;
    given without ``start``, the palm starts at the safe distance from T against it, facing T);
    ``turn_deg`` (-180 to 180, not with ``start`` or ``normal``) turns the default start away from T
    about the palm's y axis, as :func:`start_pose` does.
    """
    hand = hand if hand is not None else Hand()
    name, obj, repairs = load_object(spec, scale)
    builtin = objects.BUILTINS.get(os.fspath(spec))
    if target is not None:
        t = _finite("target", target)
    elif builtin is not None:
        t = np.asarray(builtin.target, dtype=np.float64) * float(scale)
    else:
        t = interior_target(obj)
    if not bool(obj.inside(t[None])[0]):
        raise ValueError(f"target T {t.tolist()} is not inside {name}")
    turn_deg = _turn(turn_deg)
    if turn_deg and (start is not None or normal is not None):
        raise ValueError("turn_deg (--turn) applies to the default start only, not with start or normal")
    if start is None and normal is None:
        approach = builtin.approach if builtin is not None else (0.0, 0.0, 1.0)
        pose = start_pose(obj, hand, t, approach, turn_deg)
    else:
        p = _finite("start", start) if start is not None else t - safe_distance(obj, hand, t) * _unit("normal", normal)
        n = _unit("normal", normal) if normal is not None else _unit("start - target", t - p)
        pose = look_at(p, p + n)
    return Case(name=name, obj=obj, target=t, palm_pose=pose, repairs=repairs, hand=hand)


class ImplausibleSize(ValueError):
    """A case refused for its object's size, implausible for a hand (millimetres read as metres:
    :data:`hugger.hand.PLAUSIBLE_SIZE`). ``what`` names the object and its size."""

    def __init__(self, what: str) -> None:
        super().__init__(f"{what}; refused (give a scale, or force=True to take it anyway)")
        self.what = what


def judged_case(spec: str | os.PathLike[str], hand: Hand | None = None, scale: float = 1.0, force: bool = False,
                **kwargs: Any) -> tuple[Case, str | None]:
    """:func:`default_case` (``kwargs``: target, start, normal, turn_deg) with its object's size
    judged: a size implausible for a hand raises :class:`ImplausibleSize` unless ``force``.
    Returns the case and the size's warning (None for a plausible size), for the caller to tell,
    as it tells the case's repairs."""
    import warnings

    from .hand import implausible_size

    with warnings.catch_warnings():  # the object's own warning of its size: judged here
        warnings.filterwarnings("ignore", message=r".*implausibly", category=UserWarning)
        case = default_case(spec, hand, scale=scale, **kwargs)
    message = implausible_size(case.name, float(np.ptp(case.obj.bounds, axis=0).max()))
    if message and not force:
        raise ImplausibleSize(message)
    return case, message


def _finite(name: str, value: Any) -> np.ndarray:
    try:
        a = real_array(name, value).reshape(3)
    except ValueError:
        raise ValueError(f"{name} must be three numbers") from None
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {a.tolist()}")
    return a


def _unit(name: str, value: Any) -> np.ndarray:
    a = _finite(name, value)
    if not np.any(a):
        raise ValueError(f"{name} must be a non-zero vector")
    with np.errstate(over="ignore", under="ignore"):
        n = float(_stable.norm(a))
    if not 1e-150 < n < 1e150:  # its square over- or underflowed: scaled first (others keep their bits)
        a = a / np.abs(a).max()
        n = float(_stable.norm(a))
    return a / n
