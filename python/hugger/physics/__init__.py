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

The parts
---------
:mod:`~hugger.physics.mass` (volume, centre and inertia of a mesh), :mod:`~hugger.physics.decompose`
(CoACD convex pieces and their cache), :mod:`~hugger.physics.mjcf` (the model above: finger frames,
joint ranges, MJCF text, loading it), :mod:`~hugger.physics.hold` (the hold test and its robust
variant); every name is available here, as ``hugger.physics.<name>``.
"""
from __future__ import annotations

from typing import Any

from ._common import _coacd as _coacd, _floats as _floats, _index as _index, _mujoco as _mujoco
from ._common import _resets as _resets, _trajectory as _trajectory
from .decompose import COACD_SETTINGS as COACD_SETTINGS, CONVEX_RATIO as CONVEX_RATIO
from .decompose import convex_pieces, default_cache_dir
from .hold import DIRECTIONS as DIRECTIONS, MAX_DISPLACEMENT as MAX_DISPLACEMENT
from .hold import MAX_ROTATION_DEG as MAX_ROTATION_DEG, SETTLE as SETTLE, SQUEEZE_RAMP as SQUEEZE_RAMP
from .._types import CONTACT_DISTANCE as CONTACT_DISTANCE
from .hold import PERTURBATIONS
from .hold import _rotation_deg as _rotation_deg, _run_jobs as _run_jobs, _validate_job as _validate_job
from .hold import touching_fingers, validate, validate_robust
from .mass import hull_volume, mass_properties
from .mjcf import ARMATURE as ARMATURE, CONDIM as CONDIM, DAMPRATIO as DAMPRATIO, GRAVITY as GRAVITY
from .mjcf import IMPRATIO as IMPRATIO, JOINT0_RANGE as JOINT0_RANGE, JOINT_RANGE as JOINT_RANGE, KP as KP
from .mjcf import LINK_DENSITY as LINK_DENSITY, ROLLING_FRICTION as ROLLING_FRICTION, SOLIMP as SOLIMP
from .mjcf import SOLREF as SOLREF, SQUEEZE as SQUEEZE, TIMESTEP as TIMESTEP
from .mjcf import TORSIONAL_FRICTION as TORSIONAL_FRICTION, ZERO_RADIUS_SUBSTITUTE as ZERO_RADIUS_SUBSTITUTE
from .mjcf import _build_mjcf as _build_mjcf, _stub_trajectory as _stub_trajectory
from .mjcf import export_mjcf, finger_frames, joint_ranges, load_model


def __getattr__(name: str) -> Any:
    """``MujocoSkin``, ``Simulation``, ``simulate`` and ``replay`` live in :mod:`hugger.mujoco_skin`
    (the skin that senses through MuJoCo, and closed-loop hugging)."""
    if name in ("MujocoSkin", "Simulation", "simulate", "replay"):
        from .. import mujoco_skin

        return getattr(mujoco_skin, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["MujocoSkin", "Simulation", "simulate", "replay", "export_mjcf", "validate", "validate_robust", "PERTURBATIONS",
           "load_model", "convex_pieces", "mass_properties", "hull_volume",
           "finger_frames", "joint_ranges", "touching_fingers", "default_cache_dir"]
