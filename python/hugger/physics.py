"""Physics check of a grasp in MuJoCo: MJCF export and the six-direction hold test.

Needs the ``physics`` extra (``pip install 'hugger[physics]'``: MuJoCo and CoACD); both are
imported only when a function here is called, so ``import hugger`` stays light.

The model (:func:`export_mjcf`)
-------------------------------
Units: metres, kilograms, seconds, radians; world frame = the trajectory's world frame.

* **Palm**: a *mocap* body (welded to the world, moved only by setting its pose: the hand is
  held by an arm) at ``palm_pose[k]``; its geom is a cylinder of radius ``palm_radius`` and
  thickness ``palm_thickness`` whose front face is the palm frame's z = 0 plane (local z = the
  palm normal p̂, toward the object).
* **Fingers**: finger m is a chain of N bodies. Every finger body keeps the palm's orientation at
  zero angles, link n is a capsule from its body origin (joint j_mn) along local z (p̂) of length
  L_mn (centred at z = L_mn / 2, so the geom's z axis is the link direction), and the hinge of
  link n sits at j_mn with axis ``a_m = u_m × p̂`` expressed in the palm frame (u_m the finger's
  radial direction), which is normal to the finger plane Π_m. With this axis a
  positive hinge angle is flexion (docs/model.md), so ``qpos`` of the hinges *is* the trajectory's
  ``angles`` and forward kinematics reproduces its ``joints``. A link radius of 0 (zero-thickness
  links, as in the paper) is simulated with a capsule of :data:`ZERO_RADIUS_SUBSTITUTE` = 0.2 mm: a
  capsule needs a positive radius, and 0.2 mm keeps the initial overlap with the object (the plan
  touches within its 0.1 mm sensing distance) inside MuJoCo's soft-contact band.
* **Joint ranges**: joint 0 in [-π/2, π/2] (link 0 never passes behind the palm's front plane),
  the others in [-5π/6, 5π/6]; each range is widened where needed so that it holds every angle the
  trajectory uses plus the squeeze of :func:`validate`.
* **Actuators**: one position servo per hinge, ``kp`` = :data:`KP` = 5 N·m/rad, critically damped
  (``dampratio`` = 1), targets (``ctrl``) = the trajectory's angles; every hinge has an armature
  (reflected rotor inertia) of :data:`ARMATURE` = 1e-4 kg·m², which keeps the 1-2 g links stable at
  the chosen time step. 5 N·m/rad is stiff for a hand of 2 cm links: a 0.05 rad squeeze asks for
  0.25 N·m per joint, i.e. about 10 N at a 2.5 cm lever.
* **Gravity** is -9.81 m/s² along world z in the file, with full gravity compensation
  (``gravcomp`` = 1) on every finger body: the hand is held and servoed, only the object would
  fall. :func:`validate` switches gravity off (see there).
* **Object**: a free body ``object`` of mass ``object_mass`` (default 0.1 kg) whose frame is at
  the mesh's centre of volume, axes parallel to the world's, with the mesh's own inertia tensor
  (uniform density, computed from the closed mesh). Its geoms are mesh geoms. MuJoCo collides
  the *convex hull* of each mesh geom, so a non-convex object is split into convex pieces with
  CoACD (see :func:`convex_pieces`); a nearly convex one (hull volume / volume < 1.02) is one piece.
  Meshes are written inline (``<mesh vertex=... face=...>``), so the model is a single file.
* **Contacts** (hand against object only; the hand does not collide with itself: the planner
  already keeps fingers apart, and the servos hold them there): ``condim`` 4 (tangential friction
  plus torsional friction, so a single contact can resist spin), ``friction`` = (μ, 0.005 m, 0.0001 m)
  (sliding μ = ``friction``, default 0.6; torsional and rolling lengths are MuJoCo's defaults),
  elliptic friction cones with ``impratio`` 10 (less creeping slip of soft contacts under a
  sustained load), ``solref`` = (0.004 s, 1) (a time constant of 4 time steps: stiff, critically
  damped contacts), ``solimp`` = (0.95, 0.99, 0.001) (impedance from 0.95 at the surface to 0.99 at
  1 mm penetration).
* **Solver**: time step 1 ms, ``implicitfast`` integrator (implicit in the servo damping), Newton
  solver, dense Jacobians (the models are small; dense also sidesteps a sparse-factorisation bug
  of MuJoCo 4.0.0 fixed in 4.0.1).

The hold test (:func:`validate`)
--------------------------------
The protocol of current dexterous-grasp benchmarks: object 0.1 kg, μ 0.6, gravity off, a small
squeeze, then from the same settled start a force of 10x the object's weight along ±x, ±y, ±z in
turn for 2 s; held = moved < 5 cm and turned < 15°. See :func:`validate` for every detail.
"""
from __future__ import annotations

import copy
import hashlib
import json
import math
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np

from ._checks import positive as _positive
from ._rotation import quaternion_wxyz
from .trajectory import CONTACT_DISTANCE, Trajectory

#: Hinge servo stiffness (N·m/rad).
KP = 5.0
#: Servo damping ratio (1 = critically damped, MuJoCo's ``dampratio``).
DAMPRATIO = 1.0
#: Reflected rotor inertia added to every hinge (kg·m²).
ARMATURE = 1e-4
#: Capsule radius (m) used for links of radius 0.
ZERO_RADIUS_SUBSTITUTE = 2e-4
#: Density (kg/m³) of the finger links (the palm is mocap: its mass plays no part).
LINK_DENSITY = 1000.0
#: Simulation time step (s).
TIMESTEP = 1e-3
#: Contact settings written on every hand and object geom.
CONDIM = 4
TORSIONAL_FRICTION = 0.005
ROLLING_FRICTION = 0.0001
SOLREF = (0.004, 1.0)
SOLIMP = (0.95, 0.99, 0.001)
IMPRATIO = 10.0
#: Default hinge ranges (rad): joint 0, then the others.
JOINT0_RANGE = (-math.pi / 2, math.pi / 2)
JOINT_RANGE = (-5 * math.pi / 6, 5 * math.pi / 6)
#: Hull volume / mesh volume below which a mesh is treated as convex (one piece, no CoACD).
CONVEX_RATIO = 1.02
#: CoACD settings: coarse on purpose (see :func:`convex_pieces`).
COACD_SETTINGS = {"threshold": 0.1, "max_convex_hull": 16, "preprocess_mode": "off", "resolution": 1000,
                  "mcts_nodes": 10, "mcts_iterations": 60, "mcts_max_depth": 3, "seed": 0}
#: Default squeeze (rad) added in flexion to every joint of a touching finger before the test.
SQUEEZE = 0.05
#: A finger "touches" when one of its links is within this gap (m) of the object.
TOUCH_DISTANCE = CONTACT_DISTANCE
#: Squeeze ramp and settle times (s).
SQUEEZE_RAMP = 0.1
SETTLE = 0.4
#: Held = moved less than this (m) and turned less than this (degrees).
MAX_DISPLACEMENT = 0.05
MAX_ROTATION_DEG = 15.0
DIRECTIONS = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}
GRAVITY = 9.81


def _mujoco():
    try:
        import mujoco
    except ImportError as exc:
        raise ImportError("the physics check needs MuJoCo: pip install 'hugger[physics]'") from exc
    return mujoco


def _coacd():
    try:
        import coacd
    except ImportError as exc:
        raise ImportError("convex decomposition needs CoACD: pip install 'hugger[physics]' "
                          "(or pass decompose=False to use the object's convex hull)") from exc
    return coacd


# --------------------------------------------------------------------------------------------
# mesh helpers


def mass_properties(vertices: Any, faces: Any) -> tuple[float, np.ndarray, np.ndarray]:
    """Volume (m³), centre of volume (3,) and inertia tensor (3, 3) per unit density (m⁵) about
    that centre, in the mesh's frame, of a closed mesh with outward faces."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3 or len(f) == 0:
        raise ValueError("vertices must be (V, 3) and faces (F, 3), not empty")
    ref = v.mean(axis=0)
    tri = v[f] - ref  # tetrahedra (ref, a, b, c)
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    vol6 = np.einsum("ij,ij->i", a, np.cross(b, c))
    volume = float(vol6.sum() / 6.0)
    if not volume > 0:
        raise ValueError(f"the mesh encloses no positive volume ({volume:g} m^3): not closed or inside-out")
    s = a + b + c
    centre = (vol6[:, None] * s).sum(axis=0) / 24.0 / volume
    # second moment of each tetrahedron about ref: V/20 (sum p p^T + s s^T)
    second = (np.einsum("t,ti,tj->ij", vol6 / 6.0, a, a) + np.einsum("t,ti,tj->ij", vol6 / 6.0, b, b)
              + np.einsum("t,ti,tj->ij", vol6 / 6.0, c, c) + np.einsum("t,ti,tj->ij", vol6 / 6.0, s, s)) / 20.0
    second -= volume * np.outer(centre, centre)
    inertia = np.trace(second) * np.eye(3) - second
    return volume, centre + ref, inertia


def _floats(a: Any, fmt: str = "{:.17g}") -> str:
    return " ".join(fmt.format(float(x)) for x in np.asarray(a, dtype=np.float64).ravel())


def hull_volume(vertices: Any) -> float:
    """Volume (m³) of the convex hull of ``vertices`` (V, 3), as MuJoCo computes it."""
    mujoco = _mujoco()
    v = np.asarray(vertices, dtype=np.float64)
    shift = v.mean(axis=0)
    xml = (f'<mujoco><asset><mesh name="m" inertia="convex" vertex="{_floats(v - shift, "{:.9g}")}"/></asset>'
           '<worldbody><body><freejoint/><geom type="mesh" mesh="m" density="1"/></body></worldbody></mujoco>')
    return float(mujoco.MjModel.from_xml_string(xml).body_mass[1])


def default_cache_dir() -> Path:
    """Where convex decompositions are cached: ``$HUGGER_CACHE_DIR/coacd``, else
    ``$XDG_CACHE_HOME/hugger/coacd``, else ``~/.cache/hugger/coacd``."""
    if os.environ.get("HUGGER_CACHE_DIR"):
        return Path(os.environ["HUGGER_CACHE_DIR"]) / "coacd"
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "hugger" / "coacd"


def convex_pieces(vertices: Any, faces: Any, decompose: bool = True, cache_dir: str | os.PathLike | None = None,
                  convex_ratio: float = CONVEX_RATIO) -> list[tuple[np.ndarray, np.ndarray]]:
    """Convex pieces (list of (vertices, faces)) standing in for a closed mesh in MuJoCo.

    A nearly convex mesh (hull volume / mesh volume < ``convex_ratio``) and any mesh when
    ``decompose`` is False come back whole: MuJoCo then collides its convex hull. Otherwise
    CoACD splits it with :data:`COACD_SETTINGS`: a coarse concavity threshold (0.1 instead of
    CoACD's 0.05), at most 16 pieces and a short tree search, so that a 16k-triangle scan takes
    seconds, not minutes. The trade-off: concavities shallower than about a tenth of the object's
    size stay filled in, so the simulated object is slightly fuller there than the planned one
    (conservative: the hand never sinks into it). The convexity rule has a similar blind spot: a
    concavity small in volume but deep where the hand touches it (the recessed lid of a can, a
    few millimetres) is filled by the hull. Results are cached as .npz files named by a hash
    of the mesh and the settings under ``cache_dir`` (default :func:`default_cache_dir`).
    """
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    f = np.ascontiguousarray(faces, dtype=np.int64)
    if not decompose:
        return [(v, f)]
    volume = mass_properties(v, f)[0]
    if hull_volume(v) / volume < convex_ratio:
        return [(v, f)]
    key = hashlib.sha256(v.tobytes() + f.tobytes() + json.dumps(COACD_SETTINGS, sort_keys=True).encode()).hexdigest()
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    path = folder / f"{key[:32]}.npz"
    if path.is_file():
        try:
            with np.load(path, allow_pickle=False) as z:
                n = int(z["count"])
                return [(z[f"v{i}"], z[f"f{i}"]) for i in range(n)]
        except (OSError, ValueError, KeyError):
            pass  # a damaged cache entry is recomputed below
    coacd = _coacd()
    coacd.set_log_level("error")
    parts = coacd.run_coacd(coacd.Mesh(v, f), **COACD_SETTINGS)
    pieces = [(np.asarray(pv, dtype=np.float64), np.asarray(pf, dtype=np.int64)) for pv, pf in parts]
    if not pieces:
        return [(v, f)]
    try:
        folder.mkdir(parents=True, exist_ok=True)
        arrays = {"count": np.int64(len(pieces))}
        for i, (pv, pf) in enumerate(pieces):
            arrays[f"v{i}"], arrays[f"f{i}"] = pv, pf
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, path)
    except OSError:
        pass  # an unwritable cache only costs time
    return pieces


# --------------------------------------------------------------------------------------------
# MJCF export


def _trajectory(traj: Any):
    if isinstance(traj, (str, os.PathLike)):
        return Trajectory.load(traj)
    if not isinstance(traj, Trajectory):
        raise ValueError(f"traj must be a hugger.Trajectory or a path to a trajectory file, got {type(traj).__name__}")
    return traj


def _index(traj, k: Any) -> int:
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
        raise ValueError(f"k must be a whole number, got {k!r}")
    n = len(traj)
    if not -n <= int(k) < n:
        raise ValueError(f"k = {k} is out of range for a trajectory of {n} configurations")
    return int(k) % n


def finger_frames(traj: Any, k: int = -1) -> tuple[np.ndarray, np.ndarray]:
    """Roots R_m (M, 3) and hinge axes a_m (M, 3), both in the *palm* frame, derived from the
    trajectory's palm pose and joints at configuration k: R_m = T_WP⁻¹ j_m0, u_m = R_m's direction
    in the palm plane (or the hand's ``finger_directions`` for a general layout), a_m = u_m × p̂ (normal to the finger plane Π_m; positive = flexion)."""
    traj = _trajectory(traj)
    k = _index(traj, k)
    pose = traj.palm_pose[k]
    roots = (traj.joints[k, :, 0] - pose[:3, 3]) @ pose[:3, :3]
    dirs = traj.hand.get("finger_directions")
    if dirs is not None:  # a general layout (hugger.Hand.from_layout) says u_m itself
        u = np.asarray(dirs, dtype=np.float64).reshape(-1, 3)
        return roots, np.cross(u, [0.0, 0.0, 1.0])
    u = roots.copy()
    u[:, 2] = 0.0
    norm = np.linalg.norm(u, axis=1)
    if np.any(norm <= 0):
        raise ValueError("a finger root sits on the palm axis: the finger plane is undefined")
    u /= norm[:, None]
    axes = np.cross(u, [0.0, 0.0, 1.0])
    return roots, axes


def joint_ranges(traj: Any, squeeze: float = SQUEEZE) -> np.ndarray:
    """Hinge ranges (M, N, 2) in rad: the defaults (:data:`JOINT0_RANGE`, :data:`JOINT_RANGE`)
    widened to hold every angle of the trajectory plus ``squeeze``."""
    traj = _trajectory(traj)
    a = np.asarray(traj.angles, dtype=np.float64)
    _, m, n = a.shape
    lo = np.full((m, n), JOINT_RANGE[0])
    hi = np.full((m, n), JOINT_RANGE[1])
    lo[:, 0], hi[:, 0] = JOINT0_RANGE
    lo = np.minimum(lo, a.min(axis=0) - 1e-6)
    hi = np.maximum(hi, a.max(axis=0) + float(squeeze) + 1e-6)
    return np.stack([lo, hi], axis=-1)


def _build_mjcf(traj, k: int, object_mass: float, friction: float, decompose: bool, cache_dir, squeeze: float,
                kp: float = KP) -> tuple[str, dict]:
    hand = traj.hand
    m_count, n_count = int(hand["fingers"]), int(hand["links"])
    lengths = np.asarray(hand["link_lengths"], dtype=np.float64).reshape(m_count, n_count)
    radius = float(hand["link_radius"])
    sim_radius = radius if radius > 0 else ZERO_RADIUS_SUBSTITUTE
    palm_r, palm_t = float(hand["palm_radius"]), float(hand["palm_thickness"])
    pose = np.asarray(traj.palm_pose[k], dtype=np.float64)
    roots, axes = finger_frames(traj, k)
    ranges = joint_ranges(traj, squeeze)
    angles = np.asarray(traj.angles[k], dtype=np.float64)

    verts = np.asarray(traj.object_vertices, dtype=np.float64)
    faces = np.asarray(traj.object_faces, dtype=np.int64)
    volume, centre, inertia_unit = mass_properties(verts, faces)
    inertia = inertia_unit * (object_mass / volume)
    pieces = convex_pieces(verts, faces, decompose=decompose, cache_dir=cache_dir)

    f6 = lambda x: _floats(x, "{:.9g}")  # noqa: E731  meshes: sub-nanometre is plenty
    root = ET.Element("mujoco", model="hugger_grasp")
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    ET.SubElement(root, "option", timestep=repr(TIMESTEP), integrator="implicitfast", cone="elliptic",
                        impratio=repr(IMPRATIO), solver="Newton", jacobian="dense", gravity=f"0 0 {-GRAVITY!r}")
    default = ET.SubElement(root, "default")
    ET.SubElement(default, "geom", condim=str(CONDIM),
                  friction=_floats([friction, TORSIONAL_FRICTION, ROLLING_FRICTION]),
                  solref=_floats(SOLREF), solimp=_floats(SOLIMP))
    hand_default = ET.SubElement(default, "default", {"class": "hand"})
    # hand geoms: contype 2 / conaffinity 1, object geoms: contype 1 / conaffinity 2 ->
    # hand-object pairs collide, hand-hand pairs do not.
    ET.SubElement(hand_default, "geom", contype="2", conaffinity="1", density=repr(LINK_DENSITY),
                  rgba="0.85 0.65 0.5 1")
    ET.SubElement(hand_default, "joint", type="hinge", armature=repr(ARMATURE))
    ET.SubElement(hand_default, "position", kp=repr(float(kp)), dampratio=repr(DAMPRATIO))
    obj_default = ET.SubElement(default, "default", {"class": "object"})
    ET.SubElement(obj_default, "geom", type="mesh", contype="1", conaffinity="2", rgba="0.3 0.5 0.8 1")

    asset = ET.SubElement(root, "asset")
    for i, (pv, pf) in enumerate(pieces):
        ET.SubElement(asset, "mesh", name=f"object_{i}", vertex=f6(pv - centre), face=" ".join(map(str, pf.ravel())))

    world = ET.SubElement(root, "worldbody")
    ET.SubElement(world, "light", pos=_floats(pose[:3, 3] + [0, 0, 0.5]), dir="0 0 -1", directional="true")
    palm = ET.SubElement(world, "body", name="palm", mocap="true", pos=_floats(pose[:3, 3]),
                         quat=_floats(quaternion_wxyz(pose[:3, :3])))
    ET.SubElement(palm, "geom", {"class": "hand", "name": "palm", "type": "cylinder",
                                 "pos": _floats([0, 0, -palm_t / 2]), "size": _floats([palm_r, palm_t / 2])})
    for m in range(m_count):
        parent, pos = palm, roots[m]
        for n in range(n_count):
            body = ET.SubElement(parent, "body", name=f"f{m}_l{n}", pos=_floats(pos), gravcomp="1")
            ET.SubElement(body, "joint", {"class": "hand", "name": f"f{m}_j{n}", "axis": _floats(axes[m]),
                                          "range": _floats(ranges[m, n])})
            ET.SubElement(body, "geom", {"class": "hand", "name": f"f{m}_l{n}", "type": "capsule",
                                         "pos": _floats([0, 0, lengths[m, n] / 2]),
                                         "size": _floats([sim_radius, lengths[m, n] / 2])})
            parent, pos = body, np.array([0.0, 0.0, lengths[m, n]])
    obj = ET.SubElement(world, "body", name="object", pos=_floats(centre))
    ET.SubElement(obj, "freejoint", name="object")
    ET.SubElement(obj, "inertial", pos="0 0 0", mass=repr(float(object_mass)),
                  fullinertia=_floats([inertia[0, 0], inertia[1, 1], inertia[2, 2],
                                       inertia[0, 1], inertia[0, 2], inertia[1, 2]]))
    for i in range(len(pieces)):
        ET.SubElement(obj, "geom", {"class": "object", "name": f"object_{i}", "mesh": f"object_{i}"})

    actuator = ET.SubElement(root, "actuator")
    for m in range(m_count):
        for n in range(n_count):
            ET.SubElement(actuator, "position", {"class": "hand", "name": f"f{m}_a{n}", "joint": f"f{m}_j{n}",
                                                 "ctrlrange": _floats(ranges[m, n])})
    keyframe = ET.SubElement(root, "keyframe")
    qpos = np.concatenate([angles.ravel(), centre, [1.0, 0.0, 0.0, 0.0]])
    ET.SubElement(keyframe, "key", name="grasp", qpos=_floats(qpos), ctrl=_floats(angles.ravel()),
                  mpos=_floats(pose[:3, 3]), mquat=_floats(quaternion_wxyz(pose[:3, :3])))
    ET.indent(root)
    header = (f"<!-- hugger grasp: configuration {k} of {len(traj)}, {m_count} fingers x {n_count} links, "
              f"object {object_mass:g} kg in {len(pieces)} convex piece(s). Units m, kg, s, rad. -->\n")
    info = {"object_pieces": len(pieces), "object_centre": centre.tolist(), "link_radius_simulated": sim_radius,
            "object_inertia": inertia.tolist()}
    return header + ET.tostring(root, encoding="unicode") + "\n", info


def export_mjcf(traj: Any, path: str | os.PathLike | None = None, k: int = -1, object_mass: float = 0.1,
                friction: float = 0.6, decompose: bool = True, *, cache_dir: str | os.PathLike | None = None) -> str:
    """The hand and object of ``traj`` at configuration ``k`` as a MuJoCo MJCF model (XML text).

    ``traj`` is a :class:`hugger.Trajectory` or the path of a trajectory file. The model is
    described in this module's docstring: a mocap palm at ``palm_pose[k]``, capsule links on hinges
    whose ``qpos`` equals ``angles`` (rad, positive = flexion), position servos targeting
    ``angles[k]``, and the object as a free body of ``object_mass`` kg with sliding friction
    ``friction``, split into convex pieces with CoACD when ``decompose`` and the mesh is not nearly
    convex (cached under ``cache_dir``). The keyframe ``grasp`` holds configuration k. The text is
    also written to ``path`` when given. Raises ``ValueError`` for bad input, ``ImportError`` when
    MuJoCo or CoACD are missing.
    """
    traj = _trajectory(traj)
    k = _index(traj, k)
    object_mass = _positive("object_mass", object_mass)
    friction = _positive("friction", friction)
    _mujoco()
    xml, _ = _build_mjcf(traj, k, object_mass, friction, bool(decompose), cache_dir, SQUEEZE)
    if path is not None:
        Path(path).write_text(xml)
    return xml


# --------------------------------------------------------------------------------------------
# validation


def _rotation_deg(q0: np.ndarray, q1: np.ndarray) -> float:
    """Angle (degrees) of the rotation between two unit quaternions (w, x, y, z)."""
    dot = abs(float(np.dot(q0, q1)) / (np.linalg.norm(q0) * np.linalg.norm(q1)))
    return math.degrees(2.0 * math.acos(min(1.0, dot)))


def touching_fingers(traj: Any, k: int = -1, distance: float = TOUCH_DISTANCE) -> np.ndarray:
    """Bool (M,): fingers with a link within ``distance`` (m) of the object at configuration k."""
    traj = _trajectory(traj)
    k = _index(traj, k)
    return np.asarray(traj.link_gaps(k) <= distance).any(axis=1)


def validate(traj: Any, k: int = -1, squeeze: float = SQUEEZE, force_factor: float = 10.0, duration: float = 2.0,
             mu: float = 0.6, mass: float = 0.1, *, decompose: bool = True,
             cache_dir: str | os.PathLike | None = None, kp: float = KP, force: float | None = None) -> dict:
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
       +y, -y, +z, -z (world axes) for ``duration`` s (default 2). The direction holds when the
       object's centre of mass moved less than 5 cm and it turned less than 15° from the settled
       state. ``force`` (N), when given, replaces ``force_factor`` x weight (so that the push
       stays the same when ``mass`` is perturbed). ``kp`` is the servo stiffness (N·m/rad).

    Returns a JSON-serialisable dict: ``held`` (all six hold), ``directions`` (``"+x"`` ...
    each ``{"displacement_m", "rotation_deg", "held"}``), ``settle`` (how far the squeeze moved
    the object: ``displacement_m``, ``rotation_deg``), ``touching_fingers`` and ``settings`` (every
    setting used). A direction whose simulation diverged reports ``None`` figures, ``"diverged":
    True`` and is not held. MuJoCo is deterministic here: the same input gives the identical output.
    """
    mujoco = _mujoco()
    traj = _trajectory(traj)
    k = _index(traj, k)
    squeeze = _positive("squeeze", squeeze, allow_zero=True)
    force_factor = _positive("force_factor", force_factor, allow_zero=True)
    duration = _positive("duration", duration)
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
    directions = {}
    for name, axis in DIRECTIONS.items():
        d = copy.copy(start)
        d.xfrc_applied[obj, :3] = force * np.asarray(axis, dtype=np.float64)
        mujoco.mj_step(model, d, nstep=steps)
        mujoco.mj_forward(model, d)
        disp = float(np.linalg.norm(d.xpos[obj] - pos_s))
        rot = _rotation_deg(quat_s, d.xquat[obj])
        if math.isfinite(disp) and math.isfinite(rot):
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
        "squeeze_rad": squeeze, "touch_distance_m": TOUCH_DISTANCE, "squeeze_ramp_s": SQUEEZE_RAMP,
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


def _validate_job(job: tuple) -> dict:
    traj, k, kwargs = job
    return validate(traj, k, **kwargs)


def _run_jobs(jobs: list[tuple], workers: int) -> list[dict]:
    """validate() over many (traj, k, kwargs) jobs: a process pool when workers > 1 (MuJoCo holds
    the GIL through a whole mj_step batch, so threads would not help), in order."""
    if workers <= 1 or len(jobs) <= 1:
        return [_validate_job(j) for j in jobs]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=min(workers, len(jobs)), mp_context=multiprocessing.get_context("spawn")) as pool:
        return list(pool.map(_validate_job, jobs))


def validate_robust(traj: Any, k: int = -1, *, workers: int | None = None, bisect_steps: int = 4,
                    max_factor: float = 40.0, cache_dir: str | os.PathLike | None = None) -> dict:
    """The six-direction test of :func:`validate` under the perturbations that matter, and the
    largest push the grasp holds.

    Perturbations (:data:`PERTURBATIONS`): nominal; object mass 0.09 and 0.11 kg (±10%; the push
    stays 10 x 0.1 kg x g = 9.81 N); friction mu 0.5 and 1.0; servo stiffness ±20%; squeeze 0.03 and
    0.08 rad. They run in a process pool of ``workers`` processes (default: the CPUs available).
    The grasp is *robustly held* when it holds (all six directions) under every perturbation;
    ``held_fraction`` is the fraction of perturbations it holds under. ``max_force_N`` is the
    largest push (N, nominal settings) under which all six directions hold, found by doubling from
    9.81 N up to ``max_factor`` x the weight and then ``bisect_steps`` bisections (0 when even a
    push of ``9.81 N / 2**bisect_steps`` is lost); ``max_force_factor`` is it over the weight.
    Deterministic, like :func:`validate`.
    """
    traj = _trajectory(traj)
    k = _index(traj, k)
    if workers is None:
        try:
            workers = max(1, len(os.sched_getaffinity(0)))
        except AttributeError:
            workers = os.cpu_count() or 1
    weight = 0.1 * GRAVITY
    nominal_force = 10.0 * weight
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


def load_model(traj: Any, k: int = -1, **kwargs: Any):
    """``(mujoco.MjModel, mujoco.MjData)`` of :func:`export_mjcf`, data reset to the ``grasp``
    keyframe (configuration k) and forward kinematics done."""
    mujoco = _mujoco()
    model = mujoco.MjModel.from_xml_string(export_mjcf(traj, k=k, **kwargs))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)
    return model, data


def __getattr__(name: str):
    """``MujocoSkin``, ``Simulation``, ``simulate`` and ``replay`` live in :mod:`hugger.mujoco_skin`
    (the skin that senses through MuJoCo, and closed-loop hugging)."""
    if name in ("MujocoSkin", "Simulation", "simulate", "replay"):
        from . import mujoco_skin

        return getattr(mujoco_skin, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["MujocoSkin", "Simulation", "simulate", "replay", "export_mjcf", "validate", "validate_robust", "PERTURBATIONS",
           "load_model", "convex_pieces", "mass_properties", "hull_volume",
           "finger_frames", "joint_ranges", "touching_fingers", "default_cache_dir"]
