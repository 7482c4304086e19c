"""Close-until-contact baseline (GraspIt!'s AutoGrasp) for the Hugger hand, in MuJoCo: ``hugger.baselines``.

From the same start as Hugger: the palm turns to face the target T (Phase 1, exactly as
Hugger's reorientation: no point moves more than one step per configuration), then approaches
along its normal p̂ with the fingers extended until any part of the hand touches the object
(landed within the contact tolerance δ, never overshot). Then every joint of every finger flexes
at the same constant angular speed; a joint stops for good when its own link or a link distal to
it touches the object, another finger, a non-adjacent link of its own finger or the palm (gap
≤ δ), or when it reaches its flexion limit. The plan ends when every joint has stopped.

Contact is decided by MuJoCo's collision detection on the model of :func:`hugger.physics.export_mjcf`
(the object as the same convex pieces the physics check uses; hand-hand pairs enabled here), with
a detection margin so that gaps are measured before anything touches. Each touch is landed by
bisection of the step, so every emitted configuration is free of penetration (up to MuJoCo's
distance tolerance, about 1e-6 m).

The result is a :class:`hugger.Trajectory` (docs/file-format.md): phase 0 for C_init, 1 for the
reorientation, 2 for approach and closing; tip_state FROZEN during the approach, CONTACT while a
finger closes, DONE once all its joints have stopped; ``status`` ``done`` (or ``max_iterations``).
Its ``stats`` hold counts only, so the same input gives the same trajectory, bit for bit (saved,
the same bytes). The wall-clock times come with :func:`run_baseline`'s :class:`BaselineRun`:
``plan_time_s``, the planning itself (the loop of collision queries), and ``setup_time_s``,
building and compiling the MuJoCo model.

MuJoCo is imported when :func:`plan_baseline` is first called (extra: ``pip install 'hugger[physics]'``),
so importing this module needs only numpy.

    hugger baseline OBJECT [--out FILE.npz] [--validate] [--json]
    python -m hugger.baselines [--object sphere] [--out FILE.npz] [--validate] [--json]   (the same)
"""
from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import dataclass
from typing import Any, Callable, cast

import numpy as np

from . import physics
from ._rotation import axis_angle, quaternion_wxyz
from ._types import CONTACT, DONE
from .hand import Hand
from .trajectory import Trajectory
from .world import Object


#: Collision answers a scene keeps, the newest, so that a configuration asked again is not queried
#: again (a bisection's landing point, a finger's start after the one before it moved).
_KEPT_QUERIES = 64


class _Scene:
    """The MuJoCo model of hand + object used as a collision checker."""

    def __init__(self, hand: Hand, obj: Object, target: np.ndarray, pose: np.ndarray, margin: float,
                 decompose: bool, cache_dir: Any) -> None:
        mujoco = physics._mujoco("the close-until-contact baseline")

        self.mj = mujoco
        m, n = hand.fingers, hand.links
        stub = physics._stub_trajectory(hand, obj, target, pose)
        self.model, self.data = physics.load_model(stub, k=0, decompose=decompose, cache_dir=cache_dir)
        ident: Callable[[Any, str], int] = lambda kind, name: mujoco.mj_name2id(self.model, kind, name)  # noqa: E731
        obj_body = ident(mujoco.mjtObj.mjOBJ_BODY, "object")
        hand_geoms = self.model.geom_bodyid != obj_body
        # hand-hand pairs collide here too (parent-child pairs stay filtered by MuJoCo)
        self.model.geom_contype[hand_geoms] = 3
        self.model.geom_conaffinity[hand_geoms] = 3
        hand_bodies = np.unique(self.model.geom_bodyid[hand_geoms])
        self.model.body_contype[hand_bodies] = 3  # MuJoCo's broadphase filters on these body-level masks too
        self.model.body_conaffinity[hand_bodies] = 3
        self.model.geom_margin[:] = margin
        self.margin = margin
        self.link_geoms = np.array([[ident(mujoco.mjtObj.mjOBJ_GEOM, f"f{i}_l{j}") for j in range(n)] for i in range(m)])
        self.palm_geom = ident(mujoco.mjtObj.mjOBJ_GEOM, "palm")
        hinges = np.array([[ident(mujoco.mjtObj.mjOBJ_JOINT, f"f{i}_j{j}") for j in range(n)] for i in range(m)])
        self.hinge_qpos = self.model.jnt_qposadr[hinges]
        self.upper = self.model.jnt_range[hinges, 1]
        self.queries = 0  # collision queries MuJoCo ran (a configuration asked again is answered from _kept)
        self._kept: dict[tuple[bytes, bytes], np.ndarray] = {}

    def gaps(self, pose: np.ndarray, angles: np.ndarray) -> np.ndarray:
        """Gap (m) of every geom to anything it may touch (capped at the margin); read-only."""
        key = (pose.tobytes(), angles.tobytes())
        kept = self._kept.get(key)
        if kept is not None:
            return kept
        mj, d = self.mj, self.data
        d.mocap_pos[0] = pose[:3, 3]
        d.mocap_quat[0] = quaternion_wxyz(pose[:3, :3])
        d.qpos[self.hinge_qpos.ravel()] = angles.ravel()
        mj.mj_kinematics(self.model, d)
        mj.mj_collision(self.model, d)
        self.queries += 1
        out = np.full(self.model.ngeom, self.margin)
        nc = d.ncon
        if nc:
            c = d.contact
            dist = np.asarray(c.dist[:nc])
            np.minimum.at(out, np.asarray(c.geom1[:nc]), dist)
            np.minimum.at(out, np.asarray(c.geom2[:nc]), dist)
        out.flags.writeable = False
        self._kept[key] = out
        if len(self._kept) > _KEPT_QUERIES:
            del self._kept[next(iter(self._kept))]  # the oldest
        return out

    def hand_gap(self, pose: np.ndarray, angles: np.ndarray) -> float:
        g = self.gaps(pose, angles)
        return float(min(g[self.link_geoms].min(), g[self.palm_geom]))


def _land(gap: Callable[[float], float], end: float, delta: float) -> tuple[float, bool]:
    """Land a move of ``end`` (a distance or a fraction of a step) that touches: bisection for an
    ``a`` in [0, end] whose ``gap(a)`` lies in [0, delta]. Returns ``(a, True)`` when one is found
    in 60 halvings, else the largest ``a`` tried that stayed farther than delta, and False."""
    lo, hi = 0.0, end
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        g = gap(mid)
        if g > delta:
            lo = mid
        elif g >= 0:
            return mid, True
        else:
            hi = mid
    return lo, False


@dataclass(frozen=True)
class BaselineRun:
    """A baseline plan and how long it took (:func:`run_baseline`)."""

    trajectory: Trajectory
    setup_time_s: float  #: wall-clock time of building and compiling the MuJoCo model (s)
    plan_time_s: float  #: wall-clock time of the planning itself, the loop of collision queries (s)


def plan_baseline(hand: Hand, obj: Object, target: Any, palm_pose: Any, step: float | None = None,
                  contact_tolerance: float = 1e-4, max_iterations: int = 20000, decompose: bool = True,
                  cache_dir: Any = None) -> Trajectory:
    """Close-until-contact grasp of ``obj`` by ``hand`` from ``palm_pose`` (4, 4), aimed at ``target``.

    ``step`` (m, default shortest link / 20 as in Hugger) bounds how far any point of the hand
    moves per configuration; ``contact_tolerance`` δ (m) is the gap that counts as a touch;
    ``max_iterations`` bounds the Phase 2 configurations. Raises ``ValueError`` when T is not
    inside the object, or the hand touches the object at the start or while turning. The same
    input gives the same trajectory, bit for bit; :func:`run_baseline` also times it.
    """
    return run_baseline(hand, obj, target, palm_pose, step=step, contact_tolerance=contact_tolerance,
                        max_iterations=max_iterations, decompose=decompose, cache_dir=cache_dir).trajectory


def run_baseline(hand: Hand, obj: Object, target: Any, palm_pose: Any, step: float | None = None,
                 contact_tolerance: float = 1e-4, max_iterations: int = 20000, decompose: bool = True,
                 cache_dir: Any = None) -> BaselineRun:
    """:func:`plan_baseline` (the same arguments and errors), timed: its trajectory with the
    wall-clock times of the setup and of the planning, which the trajectory does not hold."""
    t_setup = time.perf_counter()
    target = np.asarray(target, dtype=np.float64).reshape(3)
    pose = np.array(palm_pose, dtype=np.float64).reshape(4, 4)
    lengths = hand.link_lengths
    s = float(step) if step is not None else float(lengths.min()) / 20.0
    delta = float(contact_tolerance)
    if not (s > 0 and delta > 0 and math.isfinite(s) and math.isfinite(delta)):
        raise ValueError("step and contact_tolerance must be positive and finite")
    if target.shape != (3,) or not np.all(np.isfinite(target)) or not bool(obj.inside(target[None])[0]):
        raise ValueError(f"target T {target.tolist()} must be a finite point inside the object")
    m_count, n_count = hand.fingers, hand.links
    scene = _Scene(hand, obj, target, pose, margin=2 * s + 2 * delta, decompose=decompose, cache_dir=cache_dir)
    setup_time = time.perf_counter() - t_setup

    t0 = time.perf_counter()
    angles = np.zeros((m_count, n_count))
    poses, angle_list, states, phases = [pose.copy()], [angles.copy()], [np.zeros(m_count, np.int8)], [0]

    def emit(p: np.ndarray, a: np.ndarray, st: np.ndarray, ph: int) -> None:
        poses.append(p.copy())
        angle_list.append(a.copy())
        states.append(st.copy())
        phases.append(ph)

    if scene.hand_gap(pose, angles) <= delta:
        raise ValueError("the hand touches the object at the start: start farther away")
    # Phase 1: turn about P_o until p-hat points at T, no point moving more than s per increment.
    to_t = target - pose[:3, 3]
    normal = pose[:3, 2]
    alpha = math.acos(cast(float, max(-1.0, min(1.0, float(normal @ to_t) / np.linalg.norm(to_t)))))
    state = np.zeros(m_count, np.int8)
    if alpha > 1e-12:
        axis = np.cross(normal, to_t)
        if np.linalg.norm(axis) < 1e-12:
            axis = pose[:3, 0]
        extent = math.hypot(hand.palm_radius + hand.link_radius, hand.reach + hand.link_radius)
        extent = max(extent, math.hypot(hand.palm_radius, hand.palm_thickness))
        count = max(1, math.ceil(alpha * extent / s))
        r0 = pose[:3, :3].copy()
        for i in range(1, count + 1):
            p = pose.copy()
            p[:3, :3] = axis_angle(axis, alpha * i / count) @ r0
            if scene.hand_gap(p, angles) <= 0:
                raise ValueError("the hand would hit the object while turning to face the target: start farther away")
            emit(p, angles, state, 1)
        pose = poses[-1].copy()
        pose[:3, :3] = axis_angle(axis, alpha) @ r0
        poses[-1] = pose.copy()

    # Phase 2a: approach along p-hat until a touch, landed within delta by bisection.
    normal = pose[:3, 2]
    iterations = 0
    touched = False
    while iterations < max_iterations:
        def moved(a: float) -> np.ndarray:
            p = pose.copy()
            p[:3, 3] += a * normal
            return p
        if scene.hand_gap(moved(s), angles) > delta:
            pose = moved(s)
        else:
            a, landed = _land(lambda t: scene.hand_gap(moved(t), angles), s, delta)
            pose = moved(a)
            touched = landed or scene.hand_gap(pose, angles) <= delta
        iterations += 1
        emit(pose, angles, state, 2)
        if touched:
            break
    approach_configurations = iterations

    # Phase 2b: close every joint at the same angular speed until it (or a distal link) touches.
    levers = np.cumsum(lengths[:, ::-1], axis=1)[:, ::-1].sum(axis=1)  # sum over joints of the distance to the tip
    dtheta = s / float(levers.max())
    active = np.ones((m_count, n_count), dtype=bool) if touched else np.zeros((m_count, n_count), dtype=bool)
    if touched:
        state = np.full(m_count, CONTACT, np.int8)
    link_geoms = scene.link_geoms

    def stop_touching(m: int, gaps: np.ndarray) -> None:
        first = int(np.argmax(active[m])) if active[m].any() else n_count
        touching = np.flatnonzero(gaps[link_geoms[m]] <= delta)
        touching = touching[touching >= first]
        if len(touching):
            active[m, : int(touching.max()) + 1] = False

    def proposal(m: int, frac: float) -> np.ndarray:
        a = angles.copy()
        a[m] = np.minimum(angles[m] + frac * dtheta * active[m], scene.upper[m])
        return a

    while active.any() and iterations < max_iterations:
        # all fingers together when that is free; otherwise finger by finger with bisection
        trial = angles.copy()
        trial[active] += dtheta
        trial = np.minimum(trial, scene.upper)
        gaps = scene.gaps(pose, trial)
        moving = np.zeros((m_count, n_count), dtype=bool)
        for m in range(m_count):
            if active[m].any():
                moving[m, int(np.argmax(active[m])):] = True
        if np.all(gaps[link_geoms][moving] > delta):
            angles = trial
        else:
            for m in range(m_count):
                while active[m].any():
                    g_now = scene.gaps(pose, angles)
                    before = active[m].copy()
                    stop_touching(m, g_now)
                    if not np.array_equal(before, active[m]):
                        continue
                    first = int(np.argmax(active[m]))
                    g_full = scene.gaps(pose, proposal(m, 1.0))
                    if g_full[link_geoms[m, first:]].min() > delta:
                        angles = proposal(m, 1.0)
                        break
                    found, _ = _land(lambda t: float(scene.gaps(pose, proposal(m, t))[link_geoms[m, first:]].min()),
                                     1.0, delta)
                    angles = proposal(m, found)
                    stop_touching(m, scene.gaps(pose, angles))
                    break
        active &= angles < scene.upper - 1e-12  # joints at their flexion limit stop
        for m in range(m_count):
            if state[m] == CONTACT and not active[m].any():
                state[m] = DONE
        iterations += 1
        emit(pose, angles, state, 2)
    plan_time = time.perf_counter() - t0

    palm = np.array(poses)
    ang = np.array(angle_list)
    joints = np.array([hand.forward(p, a) for p, a in zip(palm, ang)])
    params = {"planner": "close-until-contact baseline (AutoGrasp)", "step": s, "epsilon": s / 10.0,
              "contact_tolerance": delta, "max_iterations": int(max_iterations), "joint_step_rad": dtheta,
              "collision": "MuJoCo, object as convex pieces", "decompose": bool(decompose)}
    stats = {"approach_configurations": approach_configurations,
             "closing_configurations": iterations - approach_configurations, "collision_queries": scene.queries,
             "touched": bool(touched), "phase1_configurations": int(np.sum(np.array(phases) == 1))}
    traj = Trajectory(hand_json=hand.to_json(), params_json=json.dumps(params), object_vertices=obj.vertices,
                      object_faces=obj.faces, target=target, palm_pose=palm, joints=joints, angles=ang,
                      tip_state=np.array(states, dtype=np.int8), phase=np.array(phases, dtype=np.int8),
                      status="done" if touched and not active.any() else "max_iterations",
                      stats_json=json.dumps(stats))
    return BaselineRun(traj, setup_time_s=setup_time, plan_time_s=plan_time)


def main(argv: list[str] | None = None) -> int:
    """``python -m hugger.baselines [--object NAME] [options of hugger baseline]``: ``hugger
    baseline NAME`` (sphere by default), whose errors, outputs and exit status it shares."""
    from .cli import main as cli_main

    args = list(sys.argv[1:] if argv is None else argv)
    name = "sphere"
    for i, arg in enumerate(args):
        if arg == "--object" or arg.startswith("--object="):
            given = arg.partition("=")[2] if "=" in arg else (args[i + 1] if i + 1 < len(args) else "")
            if not given:
                print("hugger: error: --object needs a built-in object name or a mesh file", file=sys.stderr)
                return 2
            name = given
            del args[i:i + (1 if "=" in arg else 2)]
            break
    return cli_main(["baseline", name, *args], program=argv is None)


if __name__ == "__main__":
    raise SystemExit(main())
