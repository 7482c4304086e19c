"""The planner front end: Phase 1 (reorientation) and Phase 2 (approach and hugging)."""
from __future__ import annotations

import json
import threading
from typing import Any, Iterator, Mapping, Sequence, cast

import numpy as np

from . import _core, _stable
from ._checks import real_array
from ._types import CONTACT, DONE, FROZEN, Configuration  # noqa: F401  (hugger.planner.FROZEN as before)
from .hand import Hand
from .trajectory import Trajectory
from .world import Object


def look_at(position: Any, target: Any, up: Any = None) -> np.ndarray:
    """A palm pose (4, 4) at ``position`` whose normal (z axis) points at ``target``."""
    p = real_array("position", position).reshape(3)
    z = real_array("target", target).reshape(3) - p
    length = float(_stable.norm(z))  # not np.linalg.norm, whose BLAS rounds per processor
    if not np.all(np.isfinite(z)) or length == 0:
        raise ValueError("position and target must be finite and distinct")
    z /= length
    u = np.array([0.0, 0.0, 1.0]) if up is None else real_array("up", up).reshape(3)
    if not np.all(np.isfinite(u)):
        raise ValueError(f"up must be a finite 3-vector, got {u.tolist()}")
    if float(_stable.norm(np.cross(u, z))) < 1e-6:
        u = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(u, z)
    x /= _stable.norm(x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, np.cross(z, x), z, p
    return pose


#: The rule sets of Phase 2 (docs/algorithm.md): the paper's rules with the documented decisions,
#: and those plus the extensions for firmer hugs (the default).
RULES: tuple[str, ...] = _core.RULES

#: Largest ``max_iterations`` accepted (a plan that long would take hours); the engine's limit.
MAX_ITERATIONS: int = _core.MAX_ITERATIONS
#: Smallest ``contact_tolerance`` relative to the scene's largest coordinate (m / m): below it the
#: sensing distance drowns in rounding of double-precision positions and the approach never lands.
MIN_RELATIVE_TOLERANCE = 1e-10
#: The sensing skins a plan can use: ``section`` answers Phase 2 in each finger plane by exact 2D
#: geometry (docs/performance.md), ``mesh`` by 3D queries on the mesh (the reference).
SKINS: tuple[str, ...] = _core.SKINS
DEFAULT_SKIN = "section"
#: The planner's parameters: the keywords of Planner after its first four (record_object aside).
PARAMS = ("step", "epsilon", "contact_tolerance", "max_iterations", "rules", "skin")


def check_sources(hand: Any, obj: Any) -> None:
    """``ValueError`` unless ``hand`` is a :class:`hugger.Hand` and ``obj`` a :class:`hugger.Object`
    or a Sensing skin: what :class:`Planner` plans with."""
    if not isinstance(hand, Hand):
        raise ValueError(f"hand must be a hugger.Hand, got {type(hand).__name__}")
    if not isinstance(obj, (Object, _core.Sensing)):
        raise ValueError(f"obj must be a hugger.Object or a hugger.skins.Sensing skin, got {type(obj).__name__}")


def check_case(hand: Any, obj: Any, target: Any, palm_pose: Any, record_object: Any = None) -> None:
    """``ValueError``, saying what is wrong, unless :class:`Planner` takes these arguments (up to
    its parameters, :func:`check_params`): :func:`check_sources`, T a finite point inside an Object
    (with a skin, T is taken as given), a rigid palm pose and :func:`check_record_object`.
    ``plan_many`` asks it of every case before it plans any."""
    check_sources(hand, obj)
    check_record_object(obj, record_object)
    _core.check_target(real_array("target", target), obj._core if isinstance(obj, Object) else None)
    _core.check_pose(real_array("palm_pose", palm_pose))


def check_record_object(obj: Any, record_object: Any) -> None:
    """``ValueError`` unless ``record_object`` is None, or a :class:`hugger.Object` given with a skin
    without a mesh (``obj`` a Sensing skin): the mesh such a plan records."""
    if record_object is None:
        return
    if not isinstance(record_object, Object):
        raise ValueError(f"record_object must be a hugger.Object or None, got {type(record_object).__name__}")
    if isinstance(obj, Object):
        raise ValueError("record_object must be None with an Object, whose plan records that object: it is for a "
                         "skin without a mesh")


def check_params(params: Mapping[str, Any], what: str = "planner parameters", also: Sequence[str] = (),
                 hand: Hand | None = None) -> None:
    """Raise ValueError, saying what is wrong, unless ``params`` are planner parameters (names of
    PARAMS, or of ``also``, which are not checked further; values None or as Planner takes them)
    with values Planner would take: the check of many plans before any is made. With ``hand``,
    also against that hand (a step no longer than its shortest link, contact_tolerance below the
    step, epsilon at most the step). (Planner checks contact_tolerance against the scene too.)"""
    bad = set(params) - set(PARAMS) - set(also)
    if bad:
        raise ValueError(f"unknown {what} {sorted(bad)}; expected some of {[*PARAMS, *also]}")
    skin = params.get("skin")
    if skin is not None and skin not in SKINS:
        raise ValueError(f"skin must be one of {list(SKINS)} or None (the default), got {skin!r}")
    checked = _core.PlannerParams(step=params.get("step"), epsilon=params.get("epsilon"),
                                  contact_tolerance=params.get("contact_tolerance"),
                                  max_iterations=params.get("max_iterations"), rules=params.get("rules"))
    if hand is not None:
        _core.resolve_params(hand._core, checked)


def _timeout(value: Any) -> float | None:
    """A plan timeout in seconds: None, or a positive finite number (the engine's rule)."""
    return None if value is None else _core.check_timeout(value)


def _fields(record: Any) -> dict[str, Any]:
    """The fields of a typed engine record (PlannerParams, PlannerStats) as a dict, in their C++ order."""
    return {name: getattr(record, name) for name in vars(type(record)) if not name.startswith("_")}


class Planner:
    """Plans a hugging grasp of ``obj`` by ``hand``, told only the point ``target`` inside it.

    ``obj`` is a :class:`hugger.Object` (the planner senses it through the section skin, or with
    ``skin="mesh"`` the simulated mesh world) or any skin, a :class:`hugger.skins.Sensing`
    (docs/skins.md): an analytic shape, a sensor model, a simulator, a real tactile hand. A skin
    need not have a mesh; ``record_object`` (a :class:`hugger.Object`) is then the mesh saved
    with the plan for the record and the checker (without it the trajectory is object-free; a
    :func:`hugger.skins.MeshSkin` of an Object, and a :class:`hugger.skins.SensorModel` made from
    either, record that Object). An
    exception raised by a skin reaches the caller of ``step()``/``plan()`` unchanged and ends the
    plan (status ``error``; the configurations completed before it stay valid).

    ``palm_pose`` (4, 4) is the initial palm pose T_WP (fingers extended). Defaults:
    ``step`` = shortest link / 20, ``epsilon`` = step / 10, ``contact_tolerance`` = 1e-4 m,
    ``max_iterations`` = 20000 Phase 2 iterations, ``rules`` = ``"hug"`` (``"paper"``: the 1994
    method with the documented decisions only; see docs/algorithm.md; None, as for the others,
    is the default), ``skin`` = ``"section"``
    (how an Object is sensed: exact 2D geometry in each finger plane; see docs/performance.md)
    or ``"mesh"`` (exact 3D queries, the reference, slower). Raises ``ValueError`` for bad input, T
    outside O, or a hand that touches O at the start or while turning in Phase 1.

    ``step()`` returns the next :class:`Configuration` (or None at the end), so a plan can
    stream to a robot; ``plan()`` runs to the end with the GIL released and returns the
    :class:`Trajectory`.
    """

    def __init__(self, hand: Hand, obj: Any, target: Any, palm_pose: Any, step: float | None = None,
                 epsilon: float | None = None, contact_tolerance: float | None = None,
                 max_iterations: int | None = None, rules: str | None = "hug", skin: str | None = None,
                 record_object: Object | None = None) -> None:
        check_sources(hand, obj)
        check_record_object(obj, record_object)
        sensing = None
        if isinstance(obj, _core.Sensing):
            if skin is not None:
                raise ValueError("skin= chooses how an Object is sensed; a Sensing skin is used as given")
            sensing, obj = obj, record_object
        t = real_array("target", target)
        pose = real_array("palm_pose", palm_pose)
        # The engine checks the parameters (the rules too), the skin's name, T and the pose
        # (ValueError saying what is wrong), then plans Phase 1.
        params = _core.PlannerParams(step=step, epsilon=epsilon, contact_tolerance=contact_tolerance,
                                     max_iterations=max_iterations, rules=rules)
        # The contact tolerance in force (given, or the default), by the engine's rule.
        tolerance = cast(float, _core.resolve_params(hand._core, params).contact_tolerance)  # (resolved: a number)
        from .skins.mesh import recorded_object
        from .skins.sensor import SensorModel

        if sensing is not None and obj is None:
            obj = recorded_object(sensing)  # a MeshSkin, or a sensor model of one, records its Object
        if isinstance(sensing, SensorModel):  # (the engine would find every part touching at the start)
            if not sensing.range > tolerance:
                raise ValueError(f"the SensorModel's range ({sensing.range:g} m) must exceed the planner's "
                                 f"contact_tolerance ({tolerance:g} m): every part within range reads as touching")
        self._core = _core.Planner(hand._core, cast(Object, obj)._core if sensing is None else sensing, t, pose,
                                   params, DEFAULT_SKIN if skin is None else skin)
        # What only Python sees: the recorded mesh's extent, with T's and the start's (checked by the
        # engine), against the tolerance in force.
        extent = max(1.0, float(np.abs(obj.vertices).max()) if obj is not None else 0.0,
                     float(np.abs(pose[:3, 3]).max()), float(np.abs(t).max()))
        if tolerance < MIN_RELATIVE_TOLERANCE * extent:
            default = "" if params.contact_tolerance is not None else " (the default)"
            raise ValueError(f"contact_tolerance {tolerance:g} m{default} is below the resolution this scene allows "
                             f"({MIN_RELATIVE_TOLERANCE:g} x its largest coordinate, {extent:g} m)")
        self.hand, self.object, self.sensing, self.target = hand, obj, sensing, t
        # The parameters are fixed once the planner is made: their JSON, which every trajectory
        # records, is made once, here.
        self._params_json = json.dumps(self.params)
        # Configurations handed out (by step(), or all of them by plan()): the index step() hands
        # out next, and the end of trajectory().
        self._handed = 0

    @property
    def status(self) -> str:
        """``running`` until the plan ends, then ``done`` (every finger DONE), ``stalled`` (nothing
        can move any more although some finger is not DONE: the plan ends rather than repeat an
        unchanged configuration), ``max_iterations``, ``timeout``, or ``error`` (a skin raised an
        exception)."""
        return self._core.status

    @property
    def params(self) -> dict[str, Any]:
        """The parameters in force, defaults resolved, and the skin (as a trajectory records them)."""
        return {**_fields(self._core.params), "skin": self._core.skin}

    @property
    def stats(self) -> dict[str, Any]:
        """Counters: Phase 1 configurations, Phase 2 iterations, first and palm contact, ..."""
        return _fields(self._core.stats)

    def step(self) -> Configuration | None:
        """The next configuration (C_init first), or None when the plan has ended. A Ctrl-C
        (KeyboardInterrupt) during a step loses nothing: the next call hands out the configuration
        that step made."""
        # By index: a configuration whose delivery a signal's exception cut short (Python raises it
        # as the engine's call returns) is handed out by the next call.
        c = self._core.configuration(self._handed)
        if c is None:
            return None
        out = Configuration(palm_pose=c.palm_pose, joints=c.joints, angles=c.angles, tip_state=c.tip_state,
                            phase=c.phase, iteration=c.iteration)
        # Last, after the only call that may raise a signal's exception: once counted, the
        # configuration is returned (no pending signal is taken between here and the caller).
        self._handed = out.iteration + 1
        return out

    def interrupt(self) -> None:
        """Stop a :meth:`plan` running in another thread (a controller's, an e-stop's) between
        iterations, as Ctrl-C stops one in the main thread: it raises ``KeyboardInterrupt`` there
        with the plan still running, and a later ``plan()`` or ``step()`` goes on to the same plan,
        bit for bit. Without a plan() running, the next plan() stops at once."""
        self._core.interrupt()

    def __iter__(self) -> Iterator[Configuration]:
        while (c := self.step()) is not None:
            yield c

    def plan(self, timeout: float | None = None) -> Trajectory:
        """Run to the end and return the whole trajectory, from C_init.

        ``timeout`` (seconds, positive finite, or None for no limit) bounds the wall-clock time of
        this call: past it the plan stops with status ``timeout`` and the trajectory holds every
        configuration planned so far (a valid, collision-free partial plan). A timed-out plan has
        ended; Phase 1 and the section skin's regions of the finger planes, both made when the
        planner was made, are not counted.
        """
        limit = _timeout(timeout)  # refused before anything changes
        try:
            self._core.plan(limit)
        finally:  # after an exception from a skin too: the configurations completed before it
            self._handed = self._core.size  # step() goes on after them
        return self.trajectory()

    def trajectory(self) -> Trajectory:
        """The configurations handed out so far (by ``step()``, or all after ``plan()``), as a
        :class:`Trajectory`."""
        h = self._core.history(0, self._handed)
        return Trajectory(
            hand_json=self.hand.to_json(),
            params_json=self._params_json,
            object_vertices=self.object.vertices if self.object is not None else np.zeros((0, 3)),
            object_faces=self.object.faces if self.object is not None else np.zeros((0, 3), dtype=np.int64),
            target=self.target,
            palm_pose=h.palm_pose,
            joints=h.joints,
            angles=h.angles,
            tip_state=h.tip_state,
            phase=h.phase,
            status=self.status,
            stats_json=self._core.stats_json,
        )



class _Batch:
    """The planners that worker threads run for one call (plan_many, search): when the call is
    interrupted (Ctrl-C reaches its thread, which waits for the workers), :meth:`stop` stops the
    running plans between iterations, and those not yet started at once, each with
    KeyboardInterrupt, so that the call ends without waiting for them."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._running: set[Planner] = set()
        self._stopped = False

    def plan(self, planner: Planner, timeout: float | None) -> Trajectory:
        with self._lock:
            if self._stopped:
                raise KeyboardInterrupt
            self._running.add(planner)
        try:
            return planner.plan(timeout)
        finally:
            with self._lock:
                self._running.discard(planner)

    def stop(self, pool: Any = None) -> None:
        """Stop the plans running, and refuse those asked for later; ``pool`` (a futures executor):
        its jobs not started are cancelled, without waiting for those running."""
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
        with self._lock:
            self._stopped = True
            for planner in self._running:
                planner.interrupt()  # (taken at its next iteration, even before it starts)


def plan(hand: Hand, obj: Object, target: Any, palm_pose: Any, timeout: float | None = None,
         **params: Any) -> Trajectory:
    """Plan in one call: ``Planner(hand, obj, target, palm_pose, **params).plan(timeout)``
    (``timeout`` bounds ``plan()``: the constructor's Phase 1 and regions come before it)."""
    limit = _timeout(timeout)  # checked before any planning
    # plan_many's check (Planner itself: Python's TypeError for an unknown keyword)
    check_params(params, also=("record_object",))
    return Planner(hand, obj, target, palm_pose, **params).plan(limit)
