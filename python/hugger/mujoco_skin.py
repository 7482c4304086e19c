"""A skin that senses through MuJoCo, and closed-loop hugging of an object that can move.

:class:`Simulation` is the hand (a mocap palm, hinge fingers on position servos, as in
:func:`hugger.physics.export_mjcf`) and the object as a free body, gravity off (the hand is held by
an arm; the object floats until something touches or pushes it). :class:`MujocoSkin` answers the
planner's queries with MuJoCo's own collision: ``mj_geomDistance`` between a probe geom (a capsule
or the palm cylinder, placed where the planner asks; it never collides in the simulation) and
each convex piece of the object *where the simulation has it now*.

:func:`simulate` runs the planner in the loop: each configuration is sent to the servos (the palm
pose to the mocap body), the simulation advances, the skin is read again from the simulated state
and the next step is planned from what is felt. :func:`replay` is the open-loop reference: a plan
made beforehand on the static mesh, played back in the same simulation. Both end with the
six-direction hold test of :func:`hugger.physics.validate`, run on the simulated state reached.

Needs the ``physics`` extra (``pip install 'hugger[physics]'``).
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, cast

import numpy as np

from . import _core
from . import physics as _ph
from ._checks import shown
from ._rotation import quaternion_wxyz
from ._types import CONTACT_DISTANCE
from .planner import Planner
from .world import Object

#: Simulated time per planner configuration (s): the control period of the loop.
CONTROL_PERIOD = 0.02
#: Sensing distance delta (m) of the closed loop: the servos track the plan within about 0.1 mm,
#: so the fingers slide over the object at delta / 2 = 0.25 mm instead of the default 0.05 mm.
CONTACT_TOLERANCE = 5e-4
#: Extra settling time (s) after the last configuration, before the hold test.
FINAL_SETTLE = 0.3
#: distmax (m) of a query with an infinite cap: nothing in a grasp scene is farther.
FAR = 1.0
#: Damping of the object's free motion during the grasp (N·s/m, N·m·s/rad), as if it rested on an
#: unseen support: a touch or a push moves it by millimetres, not off to infinity (gravity is off).
OBJECT_DAMPING = (2.0, 2e-3)


class Simulation:
    """The MuJoCo scene of ``hand`` and ``obj`` (a :class:`hugger.Object`, its true pose), the palm
    at ``palm_pose``. ``latency`` (control periods) delays the object pose the skin reads."""

    def __init__(self, hand: Any, obj: Any, palm_pose: Any, mass: float = 0.1, mu: float = 0.6,
                 decompose: bool = True, latency: int = 0) -> None:
        mujoco = _ph._mujoco()
        self.mujoco, self.hand, self.obj = mujoco, hand, obj
        pose = np.asarray(palm_pose, dtype=np.float64)
        stub = _ph._stub_trajectory(hand, obj, obj.vertices.mean(axis=0), pose)
        xml, info = _ph._build_mjcf(stub, 0, float(mass), float(mu), bool(decompose), None, 0.0)
        root = ET.fromstring(xml.split("-->", 1)[1])
        world = cast(ET.Element, root.find("worldbody"))
        probe = ET.SubElement(world, "body", name="probe", mocap="true")
        for name, kind in (("probe_capsule", "capsule"), ("probe_palm", "cylinder")):
            ET.SubElement(probe, "geom", name=name, type=kind, size="0.01 0.01", contype="0", conaffinity="0",
                          rgba="0 0 0 0")
        self.model = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
        self.model.opt.gravity[:] = 0.0
        self.body = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, "object")
        dof = self.model.body_dofadr[self.body]
        self.model.dof_damping[dof:dof + 3] = OBJECT_DAMPING[0]
        self.model.dof_damping[dof + 3:dof + 6] = OBJECT_DAMPING[1]
        self.data = mujoco.MjData(self.model)
        mujoco.mj_resetDataKeyframe(self.model, self.data, 0)
        mujoco.mj_forward(self.model, self.data)
        gid: Callable[[str], int] = lambda n: mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, n)  # noqa: E731
        self.pieces = [gid(f"object_{i}") for i in range(info["object_pieces"])]
        self.capsule_geom, self.palm_geom = gid("probe_capsule"), gid("probe_palm")
        self.link_geoms = [[gid(f"f{m}_l{n}") for n in range(hand.links)] for m in range(hand.fingers)]
        self.centre = np.asarray(info["object_centre"])  # the object's frame origin in its mesh coordinates
        self.latency = int(latency)
        if self.latency < 0:
            raise ValueError(f"latency must be >= 0 control periods, got {shown(latency)}")
        self._ctrl_to: np.ndarray | None = None
        self._poses: list[tuple[list[np.ndarray], list[np.ndarray]]] = []
        self._record_pose()
        self.time = 0.0

    # -- the simulated state ----------------------------------------------------------------
    def object_pose(self) -> np.ndarray:
        """(4, 4) the object's current pose, mapping its mesh coordinates to the world."""
        T = np.eye(4)
        R = self.data.xmat[self.body].reshape(3, 3)
        T[:3, :3] = R
        T[:3, 3] = self.data.xpos[self.body] - R @ self.centre
        return T

    def _record_pose(self) -> None:
        self._poses.append(([self.data.geom_xpos[g].copy() for g in self.pieces],
                            [self.data.geom_xmat[g].copy() for g in self.pieces]))
        del self._poses[: max(0, len(self._poses) - self.latency - 1)]

    def command(self, palm_pose: np.ndarray, angles: np.ndarray) -> None:
        """Send a configuration: the palm pose to the mocap body, the joint angles to the servos;
        the next :meth:`advance` moves the set points there linearly (a straight line in joint
        space, as the plan's motion is checked)."""
        self._ctrl_from = self.data.ctrl.copy()
        self._ctrl_to = np.clip(np.asarray(angles, dtype=np.float64).ravel(), self.model.actuator_ctrlrange[:, 0],
                                self.model.actuator_ctrlrange[:, 1])
        self._palm_from = (self.data.mocap_pos[0].copy(), self.data.mocap_quat[0].copy())
        self._palm_to = (np.asarray(palm_pose[:3, 3], dtype=np.float64), quaternion_wxyz(palm_pose[:3, :3]))

    def advance(self, seconds: float, force: np.ndarray | None = None) -> None:
        """Step the simulation by ``seconds``, with ``force`` (3,) N on the object's centre of mass;
        the set points reach the last command halfway through, then hold."""
        self.data.xfrc_applied[self.body, :3] = 0.0 if force is None else force
        steps = max(1, int(round(seconds / self.model.opt.timestep)))
        ramp = max(1, steps // 2)
        for i in range(steps):
            if self._ctrl_to is not None:
                f = min(1.0, (i + 1) / ramp)
                self.data.ctrl[:] = self._ctrl_from + f * (self._ctrl_to - self._ctrl_from)
                q = self._palm_from[1] + f * (self._palm_to[1] - self._palm_from[1])
                self.data.mocap_pos[0] = self._palm_from[0] + f * (self._palm_to[0] - self._palm_from[0])
                self.data.mocap_quat[0] = q / np.linalg.norm(q)
            self.mujoco.mj_step(self.model, self.data)
        self.mujoco.mj_forward(self.model, self.data)
        self.data.xfrc_applied[self.body, :3] = 0.0
        self.time += steps * self.model.opt.timestep
        self._record_pose()

    # -- sensing -----------------------------------------------------------------------------
    def _distance(self, probe: int, cap: float) -> tuple[float, np.ndarray | None, np.ndarray | None]:
        """Smallest signed distance from the probe geom to the object's pieces as the skin sees
        them (``latency`` periods ago), with the points (on the probe, on the object)."""
        delayed = self.latency > 0  # without latency the pose recorded last is the live one
        live = [(self.data.geom_xpos[g].copy(), self.data.geom_xmat[g].copy()) for g in self.pieces] if delayed else []
        if delayed:
            xpos, xmat = self._poses[0]
            for g, p, r in zip(self.pieces, xpos, xmat):
                self.data.geom_xpos[g], self.data.geom_xmat[g] = p, r
        fromto = np.zeros(6)
        pts: tuple[np.ndarray | None, np.ndarray | None]
        best, pts = math.inf, (None, None)
        distmax = FAR if not math.isfinite(cap) else max(cap, 0.0) + 1e-9
        try:
            for g in self.pieces:
                d = self.mujoco.mj_geomDistance(self.model, self.data, probe, g, distmax, fromto)
                if d < best:
                    best, pts = d, (fromto[:3].copy(), fromto[3:].copy())
        finally:
            for g, (p, r) in zip(self.pieces, live):  # nothing to restore without latency
                self.data.geom_xpos[g], self.data.geom_xmat[g] = p, r
        return best, pts[0], pts[1]

    def capsule_gap(self, a: np.ndarray, b: np.ndarray, radius: float,
                    cap: float) -> tuple[float, np.ndarray | None, np.ndarray | None]:
        g = self.capsule_geom
        axis = b - a
        half = 0.5 * float(np.linalg.norm(axis))
        r = max(radius, 1e-6)  # MuJoCo's capsule needs a radius; the axis distance is then d + r
        self.model.geom_size[g, :2] = (r, max(half, 1e-9))
        self.model.geom_rbound[g] = r + half
        self.data.geom_xpos[g] = 0.5 * (a + b)
        z = axis / (2 * half) if half > 0 else np.array([0.0, 0.0, 1.0])
        x = np.cross(z, [1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.cross(z, [0.0, 1.0, 0.0])
        x /= np.linalg.norm(x)
        self.data.geom_xmat[g] = np.column_stack([x, np.cross(z, x), z]).ravel()
        d, on_probe, on_obj = self._distance(g, cap + r - radius)
        return d + r - radius, on_probe, on_obj

    def palm_gap(self, pose: np.ndarray, radius: float, thickness: float, cap: float) -> float:
        g = self.palm_geom
        self.model.geom_size[g, :2] = (radius, 0.5 * thickness)
        self.model.geom_rbound[g] = math.hypot(radius, 0.5 * thickness)
        self.data.geom_xpos[g] = pose[:3, 3] - 0.5 * thickness * pose[:3, 2]
        self.data.geom_xmat[g] = pose[:3, :3].ravel()
        return self._distance(g, cap)[0]

    def link_gaps(self) -> np.ndarray:
        """(M, N) gaps (m) between the simulated links and the object, now."""
        out = np.zeros((self.hand.fingers, self.hand.links))
        fromto = np.zeros(6)
        for m, row in enumerate(self.link_geoms):
            for n, g in enumerate(row):
                out[m, n] = min(self.mujoco.mj_geomDistance(self.model, self.data, g, p, FAR, fromto)
                                for p in self.pieces)
        return out


class MujocoSkin(_core.Sensing):
    """The skin of a :class:`Simulation`: gaps by ``mj_geomDistance`` against the simulated object."""

    #: It senses a simulation that moves on between queries (see SensorModel.keeps_state).
    keeps_state = True

    def __init__(self, sim: Simulation) -> None:
        super().__init__()
        self.sim = sim

    def capsule(self, a: np.ndarray, b: np.ndarray, radius: float, cap: float = math.inf) -> _core.Touch:  # type: ignore[override]
        gap, on_probe, on_obj = self.sim.capsule_gap(a, b, radius, cap)
        if on_probe is None or not math.isfinite(gap) or gap >= FAR:
            return _core.Touch(math.inf, a, a, np.array([0.0, 0.0, 1.0]))
        d = on_probe - on_obj
        norm = float(np.linalg.norm(d))
        if norm < 1e-12:  # touching: the normal from the segment's nearest point
            ab = b - a
            t = 0.0 if not ab.any() else float(np.clip((on_obj - a) @ ab / (ab @ ab), 0.0, 1.0))
            d = a + t * ab - on_obj
            norm = float(np.linalg.norm(d))
            if norm < 1e-12:
                d, norm = np.array([0.0, 0.0, 1.0]), 1.0
        n = d / norm if gap >= 0 else -d / norm
        ab = b - a
        t = 0.0 if not ab.any() else float(np.clip((on_obj - a) @ ab / (ab @ ab), 0.0, 1.0))
        return _core.Touch(gap, a + t * ab, cast(np.ndarray, on_obj), n)

    def palm(self, pose: np.ndarray, radius: float, thickness: float, cap: float = math.inf) -> float:  # type: ignore[override]
        return self.sim.palm_gap(pose, radius, thickness, cap)


@dataclass
class LoopResult:
    """The outcome of :func:`simulate` or :func:`replay`."""

    mode: str  #: "closed" or "open"
    status: str  #: the planner's status (closed loop) or the replayed plan's
    configurations: int
    object_moved_m: float | None  #: how far the object's centre moved during the grasp (None: diverged)
    links_in_contact: int | None  #: simulated links within 1 mm of the object at the end (None: diverged)
    hold: dict[str, Any] = field(default_factory=dict)  #: the six-direction test (physics.validate's fields)
    trajectory: Any = None  #: the plan, with the object recorded where the simulation left it (as planned: diverged)

    def as_dict(self) -> dict[str, Any]:
        return {"mode": self.mode, "status": self.status, "configurations": self.configurations,
                "object_moved_m": self.object_moved_m, "links_in_contact": self.links_in_contact,
                "held": bool(self.hold.get("held", False)), "hold": self.hold}


def _push_force(palm_pose: np.ndarray, newtons: float) -> np.ndarray:
    return float(newtons) * np.asarray(palm_pose[:3, 0], dtype=np.float64)  # across the approach


def _drive(sim: Simulation, configurations: Iterable[tuple[np.ndarray, np.ndarray, np.ndarray]], push: float,
           push_duration: float) -> None:
    """Play (palm pose, angles, tip states) in ``sim``, a control period each, pushing the object
    with ``push`` N for ``push_duration`` s when the first finger touches. ``configurations`` is
    read one at a time, after the step before it: a planner in the loop senses what it did."""
    pushed = push == 0.0
    for palm_pose, angles, tip_state in configurations:
        sim.command(palm_pose, angles)
        if not pushed and np.any(tip_state != 0):
            pushed = True
            sim.advance(push_duration, _push_force(palm_pose, push))
        sim.advance(CONTROL_PERIOD)


def _finish(sim: Simulation, traj: Any, mode: str, start_centre: np.ndarray) -> LoopResult:
    """Settle, record the object where the simulation has it, and run the hold test from there."""
    import dataclasses

    sim.advance(FINAL_SETTLE)
    if _ph._resets(sim.mujoco, sim.data):  # where a reset left the object says nothing of the grasp:
        # the plan keeps the object it was planned with
        return LoopResult(mode=mode, status=traj.status, configurations=len(traj), object_moved_m=None,
                          links_in_contact=None, hold={"held": False, "diverged": True}, trajectory=traj)
    T = sim.object_pose()
    moved = dataclasses.replace(traj, object_vertices=sim.obj.vertices @ T[:3, :3].T + T[:3, 3])
    gaps = sim.link_gaps()
    return LoopResult(mode=mode, status=traj.status, configurations=len(traj),
                      object_moved_m=float(np.linalg.norm(sim.data.xpos[sim.body] - start_centre)),
                      links_in_contact=int(np.sum(gaps <= CONTACT_DISTANCE)),
                      hold=_ph.validate(moved) if len(traj) else {"held": False}, trajectory=moved)


def simulate(hand: Any, obj: Any, target: Any, palm_pose: Any, offset: Any = (0.0, 0.0, 0.0), push: float = 0.0,
             push_duration: float = 0.1, latency: int = 0, max_iterations: int = 3000, **params: Any) -> LoopResult:
    """Closed-loop hugging of ``obj`` (true pose) in MuJoCo, the planner told T = ``target`` +
    ``offset`` (m). ``push`` (N) pushes the object across the approach for ``push_duration`` s
    when the first finger touches (mid-grasp)."""

    pose = np.asarray(palm_pose, dtype=np.float64)
    sim = Simulation(hand, obj, pose, latency=latency)
    start_centre = sim.data.xpos[sim.body].copy()
    told = np.asarray(target, dtype=np.float64) + np.asarray(offset, dtype=np.float64)
    params.setdefault("contact_tolerance", CONTACT_TOLERANCE)
    planner = Planner(hand, MujocoSkin(sim), told, pose, max_iterations=max_iterations, record_object=obj, **params)
    _drive(sim, ((c.palm_pose, c.angles, c.tip_state) for c in planner), push, push_duration)
    return _finish(sim, planner.trajectory(), "closed", start_centre)


def replay(hand: Any, obj: Any, target: Any, palm_pose: Any, offset: Any = (0.0, 0.0, 0.0), push: float = 0.0,
           push_duration: float = 0.1, max_iterations: int = 3000, **params: Any) -> LoopResult:
    """Open loop: plan on the static mesh where T is believed to be (``obj`` moved by ``offset``),
    then play the plan back in the simulation of the true scene (same push as :func:`simulate`)."""

    pose = np.asarray(palm_pose, dtype=np.float64)
    off = np.asarray(offset, dtype=np.float64)
    believed = Object(obj.vertices + off, obj.faces)
    params.setdefault("contact_tolerance", CONTACT_TOLERANCE)
    traj = Planner(hand, believed, np.asarray(target, dtype=np.float64) + off, pose, max_iterations=max_iterations,
                   **params).plan()
    sim = Simulation(hand, obj, pose)
    start_centre = sim.data.xpos[sim.body].copy()
    _drive(sim, zip(traj.palm_pose, traj.angles, traj.tip_state), push, push_duration)
    import dataclasses

    traj = dataclasses.replace(traj, object_vertices=obj.vertices, object_faces=obj.faces)
    return _finish(sim, traj, "open", start_centre)


__all__ = ["CONTROL_PERIOD", "LoopResult", "MujocoSkin", "Simulation", "replay", "simulate"]
