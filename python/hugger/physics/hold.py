"""The six-direction hold test in MuJoCo (:func:`validate`), the robust verdict under perturbations
(:func:`validate_robust`), and the process pool that runs many tests."""
from __future__ import annotations

import copy
import math
import os
from typing import Any, cast

import numpy as np

from .._checks import positive as _positive, whole as _whole, workers as _workers
from .._pool import running_pool
from .._types import CONTACT_DISTANCE
from ._common import _index, _mujoco, _resets, _trajectory
from .decompose import COACD_SETTINGS, CONVEX_RATIO, convex_pieces
from .mjcf import (ARMATURE, CONDIM, DAMPRATIO, GRAVITY, IMPRATIO, KP, LINK_DENSITY, ROLLING_FRICTION, SOLIMP, SOLREF,
                   SQUEEZE, TIMESTEP, TORSIONAL_FRICTION, _build_mjcf)

#: Squeeze ramp and settle times (s).
SQUEEZE_RAMP = 0.1
SETTLE = 0.4
#: Held = moved less than this (m) and turned less than this (degrees).
MAX_DISPLACEMENT = 0.05
MAX_ROTATION_DEG = 15.0
#: The longest push a hold test simulates (s): a grasp that holds that long holds.
MAX_DURATION = 60.0
DIRECTIONS = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}


def _rotation_deg(q0: np.ndarray, q1: np.ndarray) -> float:
    """Angle (degrees) of the rotation between two unit quaternions (w, x, y, z)."""
    dot = abs(float(np.dot(q0, q1)) / (np.linalg.norm(q0) * np.linalg.norm(q1)))
    return math.degrees(2.0 * math.acos(min(1.0, float(dot))))


def touching_fingers(traj: Any, k: int = -1, distance: float = CONTACT_DISTANCE) -> np.ndarray:
    """Bool (M,): fingers with a link within ``distance`` (m) of the object at configuration k (a finger
    "touches" by the same gap as every contact of the summaries and the analysis)."""
    traj = _trajectory(traj)
    k = _index(traj, k)
    return cast(np.ndarray, np.asarray(traj.link_gaps(k) <= distance).any(axis=1))


def validate(traj: Any, k: int = -1, squeeze: float = SQUEEZE, force_factor: float = 10.0, duration: float = 2.0,
             mu: float = 0.6, mass: float = 0.1, *, decompose: bool = True,
             cache_dir: str | os.PathLike[str] | None = None, kp: float = KP,
             force: float | None = None) -> dict[str, Any]:
    """Six-direction hold test of configuration ``k`` of ``traj`` in MuJoCo.

    Protocol (as in current dexterous-grasp benchmarks):

    1. The model of :func:`export_mjcf` with an object of ``mass`` kg (default 0.1) and sliding
       friction ``mu`` (default 0.6). **Gravity is off for the whole test**, hand and object: the
       hand is held by an arm, and the six directions below replace gravity, each probing the
       grasp against a load of ``force_factor`` x the object's weight (10 x 0.1 kg x 9.81 m/s² =
       9.81 N by default) along one axis. The hand's palm is fixed (mocap).
    2. Squeeze: every joint of each finger that touches the object (a link within 1 mm) is
       commanded ``squeeze`` rad (default 0.05 rad, about 3°) further in flexion, ramped in over
       0.1 s; then 0.4 s of settling. Fingers that do not touch keep their planned angles.
    3. From this settled state (a copy of the whole ``mjData``, restored for every direction) a
       force of ``force_factor`` x weight is applied at the object's centre of mass along +x, -x,
       +y, -y, +z, -z (world axes) for ``duration`` s (default 2, at most :data:`MAX_DURATION`).
       The direction holds when the object's centre of mass moved less than 5 cm and it turned less
       than 15° from the settled state. ``force`` (N), when given, replaces ``force_factor`` x weight (so that the push
       stays the same when ``mass`` is perturbed). ``kp`` is the servo stiffness (N·m/rad).

    Returns a JSON-serialisable dict: ``held`` (all six hold), ``directions`` (``"+x"`` ...
    each ``{"displacement_m", "rotation_deg", "held"}``), ``settle`` (how far the squeeze moved
    the object: ``displacement_m``, ``rotation_deg``), ``touching_fingers`` and ``settings`` (every
    setting used). A direction whose simulation diverged reports ``None`` figures, ``"diverged":
    True`` and is not held. MuJoCo is deterministic here: the same input gives the identical output.
    """
    mujoco = _mujoco()
    traj = _trajectory(traj, needs_object=True)
    k = _index(traj, k)
    squeeze = _positive("squeeze", squeeze, allow_zero=True)
    force_factor = _positive("force_factor", force_factor, allow_zero=True)
    duration = _positive("duration", duration, most=MAX_DURATION)
    mu = _positive("mu", mu)
    mass = _positive("mass", mass)
    kp = _positive("kp", kp)

    xml, info = _build_mjcf(traj, k, mass, mu, bool(decompose), cache_dir, squeeze, kp)
    model = mujoco.MjModel.from_xml_string(xml)
    model.opt.gravity[:] = 0.0
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    obj = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "object")

    touching = touching_fingers(traj, k)
    planned = np.asarray(traj.angles[k], dtype=np.float64)
    target = planned + squeeze * touching[:, None]
    target = np.clip(target.ravel(), model.actuator_ctrlrange[:, 0], model.actuator_ctrlrange[:, 1])

    mujoco.mj_forward(model, data)
    pos0, quat0 = data.xpos[obj].copy(), data.xquat[obj].copy()
    ramp_steps = max(1, int(round(SQUEEZE_RAMP / TIMESTEP)))
    chunk = 10
    for i in range(0, ramp_steps, chunk):
        frac = min(1.0, (i + chunk) / ramp_steps)
        data.ctrl[:] = planned.ravel() + frac * (target - planned.ravel())
        mujoco.mj_step(model, data, nstep=min(chunk, ramp_steps - i))
    data.ctrl[:] = target
    mujoco.mj_step(model, data, nstep=int(round(SETTLE / TIMESTEP)))
    mujoco.mj_forward(model, data)
    start = copy.copy(data)
    pos_s, quat_s = data.xpos[obj].copy(), data.xquat[obj].copy()

    weight = mass * GRAVITY
    force = force_factor * weight if force is None else _positive("force", force, allow_zero=True)
    steps = int(round(duration / TIMESTEP))
    directions: dict[str, dict[str, Any]] = {}
    for name, axis in DIRECTIONS.items():
        d = copy.copy(start)
        d.xfrc_applied[obj, :3] = force * np.asarray(axis, dtype=np.float64)
        mujoco.mj_step(model, d, nstep=steps)
        mujoco.mj_forward(model, d)
        disp = float(np.linalg.norm(d.xpos[obj] - pos_s))
        rot = _rotation_deg(quat_s, d.xquat[obj])
        if math.isfinite(disp) and math.isfinite(rot) and _resets(mujoco, d) == _resets(mujoco, start):
            directions[name] = {"displacement_m": disp, "rotation_deg": rot,
                                "held": bool(disp < MAX_DISPLACEMENT and rot < MAX_ROTATION_DEG)}
        else:  # the simulation diverged: no figures, not held
            directions[name] = {"displacement_m": None, "rotation_deg": None, "held": False, "diverged": True}
    settings = {
        "k": k, "mass_kg": mass, "mu": mu, "torsional_friction_m": TORSIONAL_FRICTION,
        "rolling_friction_m": ROLLING_FRICTION, "condim": CONDIM, "cone": "elliptic", "impratio": IMPRATIO,
        "solref": list(SOLREF), "solimp": list(SOLIMP), "timestep_s": TIMESTEP, "integrator": "implicitfast",
        "solver": "Newton", "jacobian": "dense", "kp_Nm_per_rad": kp, "dampratio": DAMPRATIO, "armature_kgm2": ARMATURE,
        "link_density_kg_m3": LINK_DENSITY, "link_radius_simulated_m": info["link_radius_simulated"],
        "squeeze_rad": squeeze, "contact_distance_m": CONTACT_DISTANCE, "squeeze_ramp_s": SQUEEZE_RAMP,
        "settle_s": SETTLE, "gravity": "off (hand held by an arm; the six directions replace gravity)",
        "force_factor": force_factor, "force_N": force, "force_point": "object centre of mass",
        "duration_s": duration, "max_displacement_m": MAX_DISPLACEMENT, "max_rotation_deg": MAX_ROTATION_DEG,
        "decompose": bool(decompose), "object_pieces": info["object_pieces"], "convex_ratio": CONVEX_RATIO,
        "coacd": dict(COACD_SETTINGS), "hand_self_collision": False, "mujoco": mujoco.__version__,
    }
    return {
        "held": bool(all(v["held"] for v in directions.values())),
        "directions": directions,
        "settle": {"displacement_m": float(np.linalg.norm(pos_s - pos0)), "rotation_deg": _rotation_deg(quat0, quat_s)},
        "touching_fingers": [bool(x) for x in touching],
        "settings": settings,
    }


#: The perturbations of the robust verdict: name -> keyword arguments of :func:`validate`.
PERTURBATIONS = {
    "nominal": {},
    "mass-10%": {"mass": 0.09}, "mass+10%": {"mass": 0.11},
    "mu=0.5": {"mu": 0.5}, "mu=1.0": {"mu": 1.0},
    "kp-20%": {"kp": 0.8 * KP}, "kp+20%": {"kp": 1.2 * KP},
    "squeeze=0.03": {"squeeze": 0.03}, "squeeze=0.08": {"squeeze": 0.08},
}


#: The robust verdict's object mass (kg) and push (N): 10 x its weight, also when the mass is perturbed.
NOMINAL_MASS = 0.1
NOMINAL_FORCE = 10.0 * NOMINAL_MASS * GRAVITY


def _validate_job(job: tuple[Any, int, dict[str, Any]]) -> dict[str, Any]:
    traj, k, kwargs = job
    return validate(traj, k, **kwargs)


def _run_jobs(jobs: list[tuple[Any, int, dict[str, Any]]], workers: int) -> list[dict[str, Any]]:
    """validate() over many (traj, k, kwargs) jobs, in order: in a process pool when workers > 1."""
    if workers <= 1 or len(jobs) <= 1:
        return [_validate_job(j) for j in jobs]
    # Processes, not threads: MuJoCo holds the GIL through a whole mj_step batch.
    with running_pool(workers, len(jobs)) as pool:  # stopped at once when interrupted
        return list(pool.map(_validate_job, jobs))


def validate_robust(traj: Any, k: int = -1, *, workers: int | None = None, bisect_steps: int = 4,
                    max_factor: float = 40.0, cache_dir: str | os.PathLike[str] | None = None) -> dict[str, Any]:
    """The six-direction test of :func:`validate` under the perturbations that matter, and the
    largest push the grasp holds.

    Perturbations (:data:`PERTURBATIONS`): nominal; object mass 0.09 and 0.11 kg (±10%; the push
    stays 10 x 0.1 kg x g = 9.81 N); friction mu 0.5 and 1.0; servo stiffness ±20%; squeeze 0.03 and
    0.08 rad. They run in a process pool of ``workers`` processes (default: the CPUs available).
    The grasp is *robustly held* when it holds (all six directions) under every perturbation;
    ``held_fraction`` is the fraction of perturbations it holds under. ``max_force_N`` is the
    largest push (N, nominal settings) under which all six directions hold, found by doubling from
    9.81 N up to ``max_factor`` (positive) x the weight and then ``bisect_steps`` (0 to 30)
    bisections (0 when even a push of ``9.81 N / 2**bisect_steps`` is lost); ``max_force_factor``
    is it over the weight.
    Deterministic, like :func:`validate`.
    """
    traj = _trajectory(traj, needs_object=True)
    k = _index(traj, k)
    workers = _workers("workers", workers)
    bisect_steps = _whole("bisect_steps", bisect_steps, 0, 30)
    max_factor = _positive("max_factor", max_factor)
    weight = NOMINAL_MASS * GRAVITY
    nominal_force = NOMINAL_FORCE
    names = list(PERTURBATIONS)
    jobs = [(traj, k, {**PERTURBATIONS[n], "force": nominal_force, "cache_dir": cache_dir}) for n in names]
    if workers > 1:
        convex_pieces(traj.object_vertices, traj.object_faces, cache_dir=cache_dir)  # decompose once, cached
    results = dict(zip(names, _run_jobs(jobs, workers)))

    def held_at(force: float) -> bool:
        return bool(validate(traj, k, force=force, cache_dir=cache_dir)["held"])

    lo, hi = 0.0, None
    if results["nominal"]["held"]:
        lo = nominal_force
        f = 2 * nominal_force
        while f <= max_factor * weight + 1e-9:
            if held_at(f):
                lo, f = f, 2 * f
            else:
                hi = f
                break
    else:
        hi = nominal_force
    if hi is not None:
        for _ in range(int(bisect_steps)):
            mid = 0.5 * (lo + hi)
            if held_at(mid):
                lo = mid
            else:
                hi = mid
    held = [bool(results[n]["held"]) for n in names]
    return {
        "robust": all(held),
        "held_fraction": sum(held) / len(held),
        "held": bool(results["nominal"]["held"]),
        "max_force_N": lo,
        "max_force_factor": lo / weight,
        "nominal_force_N": nominal_force,
        "perturbations": {n: {"held": bool(results[n]["held"]), "changed": PERTURBATIONS[n],
                              "directions": results[n]["directions"]} for n in names},
    }
