"""The MJCF model of a grasp (described in :mod:`hugger.physics`): finger frames, joint ranges,
writing the model, and loading it in MuJoCo."""
from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from typing import Any

import numpy as np

from .._checks import positive as _positive
from .._files import write_atomic
from .._rotation import quaternion_wxyz
from ..trajectory import Trajectory
from ._common import _floats, _index, _mujoco, _trajectory
from .decompose import convex_pieces
from .mass import mass_properties

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
#: Default squeeze (rad) added in flexion to every joint of a touching finger before the test.
SQUEEZE = 0.05
GRAVITY = 9.81


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


def _build_mjcf(traj: Trajectory, k: int, object_mass: float, friction: float, decompose: bool,
                cache_dir: str | os.PathLike[str] | None, squeeze: float, kp: float = KP) -> tuple[str, dict[str, Any]]:
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

    def f6(x: Any) -> str:
        return _floats(x, "{:.9g}")  # meshes: sub-nanometre is plenty

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


def export_mjcf(traj: Any, path: str | os.PathLike[str] | None = None, k: int = -1, object_mass: float = 0.1,
                friction: float = 0.6, decompose: bool = True, *,
                cache_dir: str | os.PathLike[str] | None = None) -> str:
    """The hand and object of ``traj`` at configuration ``k`` as a MuJoCo MJCF model (XML text).

    ``traj`` is a :class:`hugger.Trajectory` or the path of a trajectory file. The model is
    described in the docstring of :mod:`hugger.physics`: a mocap palm at ``palm_pose[k]``, capsule links on hinges
    whose ``qpos`` equals ``angles`` (rad, positive = flexion), position servos targeting
    ``angles[k]``, and the object as a free body of ``object_mass`` kg with sliding friction
    ``friction``, split into convex pieces with CoACD when ``decompose`` and the mesh is not nearly
    convex (cached under ``cache_dir``). The keyframe ``grasp`` holds configuration k. The text is
    also written to ``path`` when given. Raises ``ValueError`` for bad input, ``ImportError`` when
    MuJoCo or CoACD are missing.
    """
    traj = _trajectory(traj, needs_object=True)
    k = _index(traj, k)
    object_mass = _positive("object_mass", object_mass)
    friction = _positive("friction", friction)
    _mujoco()
    xml, _ = _build_mjcf(traj, k, object_mass, friction, bool(decompose), cache_dir, SQUEEZE)
    if path is not None:
        write_atomic(path, xml)
    return xml


def _stub_trajectory(hand: Any, obj: Any, target: Any, pose: np.ndarray) -> Trajectory:
    """A one-configuration trajectory (C_init: ``hand`` at palm ``pose``, fingers straight, beside
    ``obj``) from which the MJCF model of a scene is built before there is a plan."""
    m, n = hand.fingers, hand.links
    joints = hand.forward(pose, np.zeros((m, n)))[None]
    return Trajectory(hand_json=hand.to_json(), params_json="{}", object_vertices=obj.vertices,
                      object_faces=obj.faces, target=np.asarray(target, dtype=np.float64), palm_pose=pose[None],
                      joints=joints, angles=np.zeros((1, m, n)), tip_state=np.zeros((1, m), dtype=np.int8),
                      phase=np.zeros(1, dtype=np.int8), status="start")


def load_model(traj: Any, k: int = -1, **kwargs: Any) -> tuple[Any, Any]:
    """``(mujoco.MjModel, mujoco.MjData)`` of :func:`export_mjcf`, data reset to the ``grasp``
    keyframe (configuration k) and forward kinematics done."""
    mujoco = _mujoco()
    model = mujoco.MjModel.from_xml_string(export_mjcf(traj, k=k, **kwargs))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)
    return model, data
