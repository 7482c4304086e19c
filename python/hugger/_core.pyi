"""Hugger engine: hand kinematics, the simulated world and the planner (C++17).

Type stubs for the compiled module ``hugger._core`` (written from cpp/bindings/*.cpp, started with
pybind11-stubgen). Arrays are float64 unless noted; shapes are in the docstrings.
"""
from __future__ import annotations
import numpy
import numpy.typing
import typing
__all__: list[str] = ['Configuration', 'HandModel', 'History', 'Object', 'Planner', 'PlannerParams', 'PlannerStats',
                      'QualityResult', 'Sensing', 'SimulatedWorld', 'Touch', 'check_pose', 'check_timeout',
                      'grasp_quality', 'resolve_params']
class HandModel:
    """
    Immutable hand: M fingers of N links on a round palm (metres).
    """
    @typing.overload
    def __init__(self, fingers: typing.SupportsInt | typing.SupportsIndex, links: typing.SupportsInt | typing.SupportsIndex, link_lengths: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], link_radius: typing.SupportsFloat | typing.SupportsIndex, palm_radius: typing.SupportsFloat | typing.SupportsIndex, palm_thickness: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @typing.overload
    def __init__(self, fingers: typing.SupportsInt | typing.SupportsIndex, links: typing.SupportsInt | typing.SupportsIndex, link_lengths: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], link_radius: typing.SupportsFloat | typing.SupportsIndex, palm_radius: typing.SupportsFloat | typing.SupportsIndex, palm_thickness: typing.SupportsFloat | typing.SupportsIndex, *, roots: typing.Annotated[numpy.typing.ArrayLike, numpy.float64] | None = None, directions: typing.Annotated[numpy.typing.ArrayLike, numpy.float64] | None = None, rest: typing.Annotated[numpy.typing.ArrayLike, numpy.float64] | None = None, lower: typing.Annotated[numpy.typing.ArrayLike, numpy.float64] | None = None, upper: typing.Annotated[numpy.typing.ArrayLike, numpy.float64] | None = None) -> None:
        """
        A general layout (palm frame): roots (M, 3) and directions (M, 3) with z = 0, rest angles (M, N), joint limits lower and upper (M, N) in rad (+-inf: unlimited). None: the rim layout's value.
        """
    def angles_from_joints(self, palm_pose: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], joints: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """
        Joint angles (M, N) from joint positions (M, N+1, 3).
        """
    def forward(self, palm_pose: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], angles: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """
        Joint positions (M, N+1, 3) in the world from palm pose (4, 4) and angles (M, N).
        """
    def planes(self, palm_pose: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """
        Finger planes (M, 3, 3): rows origin (the plane's point nearest P_o), outward u_m, palm normal p.
        """
    def roots(self, palm_pose: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """
        Finger roots R_m (M, 3) in the world.
        """
    @property
    def extended_radius(self) -> float:
        """
        Largest distance (m) from P_o of the hand at rest
        """
    @property
    def finger_angles(self) -> list[float]:
        ...
    @property
    def finger_directions(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        In-plane outward directions u_m (M, 3) in the palm frame
        """
    @property
    def finger_roots(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        Roots R_m (M, 3) in the palm frame (m)
        """
    @property
    def fingers(self) -> int:
        ...
    @property
    def general(self) -> bool:
        """
        True for a general layout
        """
    @property
    def has_limits(self) -> bool:
        """
        True when any joint limit is finite
        """
    @property
    def link_lengths(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @property
    def link_radius(self) -> float:
        ...
    @property
    def links(self) -> int:
        ...
    @property
    def lower(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        Lower joint limits (M, N), rad (-inf: unlimited)
        """
    @property
    def palm_radius(self) -> float:
        ...
    @property
    def palm_thickness(self) -> float:
        ...
    @property
    def rest_angles(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        Rest (FROZEN) joint angles (M, N), rad
        """
    @property
    def upper(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        Upper joint limits (M, N), rad (+inf: unlimited)
        """
class Object:
    """
    A closed, consistently oriented triangle mesh O.
    """
    def __init__(self, vertices: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], faces: typing.Annotated[numpy.typing.ArrayLike, numpy.int64]) -> None:
        ...
    def closest(self, points: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], max_distance: typing.SupportsFloat | typing.SupportsIndex = ...) -> dict[str, typing.Any]:
        """
        For points (n, 3): signed distance (n,), closest surface point (n, 3), the outward unit normal of its triangle (n, 3) and the triangle index (n,). Points farther than `max_distance` from the surface may get distance +inf or -inf (the sign still says outside or inside), NaN point and normal, and triangle -1.
        """
    def inside(self, points: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.bool_]:
        """
        True for each point (n, 3) strictly inside O.
        """
    def palm_gap(self, palm_pose: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], radius: typing.SupportsFloat | typing.SupportsIndex, thickness: typing.SupportsFloat | typing.SupportsIndex) -> float:
        """
        Gap (m) between the palm disk of pose (4, 4) and O; negative when they overlap.
        """
    def section(self, origin: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], u: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], v: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> list[numpy.typing.NDArray[numpy.float64]]:
        """
        Section of O by the plane origin + a u + b v: a list of closed loops (k, 2) in (a, b); outer loops counter-clockwise.
        """
    def section_region(self, origin: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], u: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], v: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], radius: typing.SupportsFloat | typing.SupportsIndex, flatten: typing.SupportsFloat | typing.SupportsIndex = 1e-05) -> dict[str, typing.Any]:
        """
        The section skin's region of the plane origin + a u + b v for links of `radius`: the points within `radius` of O. Returns its boundary as flattened segments (k, 2, 2) in (a, b), at most `flatten` m outside the exact curve, and their outward unit normals (k, 2).
        """
    def segment_distance(self, a: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], b: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """
        Signed distance (n,) of each segment [a_i, b_i] to O; <= 0 when it crosses the surface.
        """
    def signed_distance(self, points: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """
        Signed distance (n,) of each point (n, 3) to O's surface; negative inside.
        """
    @property
    def bounds(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        Axis-aligned bounds (2, 3): min and max corners.
        """
    @property
    def volume(self) -> float:
        """
        Enclosed volume (m^3).
        """
class Touch:
    """
    What a piece of skin senses. ``gap`` (m) between the part's surface and O: signed, negative when the part penetrates O (FCL's convention); exact when <= the query's cap, otherwise any value above cap (+inf: nothing sensed). ``on_hand`` (3,): nearest point of the capsule's axis; ``on_object`` (3,): nearest point of O; ``normal`` (3,): unit gradient of the signed distance at on_hand, pointing out of O toward the hand.
    """
    def __init__(self, gap: typing.SupportsFloat | typing.SupportsIndex, on_hand: typing.Annotated[numpy.typing.ArrayLike, numpy.float64] = ..., on_object: typing.Annotated[numpy.typing.ArrayLike, numpy.float64] = ..., normal: typing.Annotated[numpy.typing.ArrayLike, numpy.float64] = ...) -> None:
        ...
    def __repr__(self) -> str:
        ...
    @property
    def gap(self) -> float:
        ...
    @gap.setter
    def gap(self, value: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def normal(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @normal.setter
    def normal(self, value: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> None:
        ...
    @property
    def on_hand(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @on_hand.setter
    def on_hand(self, value: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> None:
        ...
    @property
    def on_object(self) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @on_object.setter
    def on_object(self, value: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> None:
        ...
class Sensing:
    """
    The whole-sensitive skin: the planner learns the object only through it. Subclass it (calling ``super().__init__()``) and define ``capsule(a, b, radius, cap) -> Touch`` and ``palm(pose, radius, thickness, cap) -> float``; ``capsule_clear(a, b, radius, a_outside) -> bool`` may be overridden. A skin whose answers depend on the queries before them sets the class attribute ``keeps_state = True`` (hugger.plan_many then plans the cases sharing it one after another).
    """
    def __init__(self) -> None:
        ...
    def capsule(self, a: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], b: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], radius: typing.SupportsFloat | typing.SupportsIndex, cap: typing.SupportsFloat | typing.SupportsIndex = ...) -> Touch:
        """
        Gap between the capsule of axis [a, b] (3,) and ``radius`` (m) and O, as a Touch (a == b: a sphere).
        """
    def capsule_clear(self, a: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], b: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], radius: typing.SupportsFloat | typing.SupportsIndex, a_outside: bool = False) -> bool:
        """
        True when the capsule does not penetrate O (gap >= 0). The default asks capsule(..., cap=0).
        """
    def palm(self, pose: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], radius: typing.SupportsFloat | typing.SupportsIndex, thickness: typing.SupportsFloat | typing.SupportsIndex, cap: typing.SupportsFloat | typing.SupportsIndex = ...) -> float:
        """
        Gap (m) between the palm disk (``radius``, ``thickness`` behind the front face of pose T_WP (4, 4)) and O; negative when they overlap (the depth need not be exact).
        """
class SimulatedWorld(Sensing):
    """
    The simulated mesh world: exact 3D queries on a BVH of the object (the reference skin).
    """
    def __init__(self, object: Object) -> None:
        ...
class PlannerParams:
    """
    The planner's parameters (docs/python.md). None selects the documented default: step = shortest link / 20, epsilon = step / 10, contact_tolerance = 1e-4 m, rules = hug. The engine checks them (hugger/planner/planner.hpp: check_params); a Planner's params have the defaults resolved.
    """
    def __init__(self, *, step: typing.SupportsFloat | None = None, epsilon: typing.SupportsFloat | None = None, contact_tolerance: typing.SupportsFloat | None = None, max_iterations: typing.SupportsInt | None = None, rules: str | None = 'hug') -> None:
        ...
    def __repr__(self) -> str:
        ...
    @property
    def step(self) -> float | None:
        """
        Fingertip step s (m); None: the default
        """
    @property
    def epsilon(self) -> float | None:
        """
        Overextension threshold (m); None: the default
        """
    @property
    def contact_tolerance(self) -> float | None:
        """
        Sensing distance delta (m); None: the default
        """
    @property
    def max_iterations(self) -> int:
        """
        Bound on Phase 2 iterations
        """
    @property
    def rules(self) -> str:
        """
        The rule set of Phase 2: 'hug' or 'paper'
        """
class PlannerStats:
    """
    Counters of one plan, for inspection and benchmarks.
    """
    def __init__(self, *args: typing.Any, **kwargs: typing.Any) -> None:
        """Not constructible from Python: read from Planner.stats."""
    @property
    def phase1_configurations(self) -> int:
        """
        Configurations of Phase 1
        """
    @property
    def phase2_iterations(self) -> int:
        """
        Phase 2 iterations
        """
    @property
    def first_contact_iteration(self) -> int:
        """
        Phase 2 iteration of the first touch (-1: none yet)
        """
    @property
    def palm_contact_iteration(self) -> int:
        """
        Phase 2 iteration at which the palm touched (-1: none yet)
        """
    @property
    def sigma_retries(self) -> int:
        """
        Palm steps refused (each step asked and refused counts)
        """
    @property
    def finger_collisions(self) -> int:
        """
        Fingers stopped by another finger or themselves
        """
    @property
    def clinging_failures(self) -> int:
        """
        Fingers stopped because no free link position was found
        """
    @property
    def motion_rejections(self) -> int:
        """
        Finger moves refused: a joint would move > 4 s, or the swept motion collides
        """
    @property
    def approach_configurations(self) -> int:
        """
        Configurations emitted by the approach before the first contact
        """
    @property
    def fingers_opened(self) -> int:
        """
        Hug rule H5: iterations in which a finger turned its root joint back to let the palm land
        """
    @property
    def reclose_steps(self) -> int:
        """
        Hug rule H5: steps closing an opened finger's root joint again
        """
class Configuration:
    """
    One hand configuration of a plan (docs/model.md).
    """
    def __init__(self, *args: typing.Any, **kwargs: typing.Any) -> None:
        """Not constructible from Python: returned by Planner.configuration."""
    @property
    def palm_pose(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        (4, 4) T_WP
        """
    @property
    def joints(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        (M, N+1, 3) joint positions in the world, tail first
        """
    @property
    def angles(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        (M, N) joint angles (rad)
        """
    @property
    def tip_state(self) -> numpy.typing.NDArray[numpy.int8]:
        """
        (M,) int8: 0 FROZEN, 1 CONTACT, 2 DONE
        """
    @property
    def phase(self) -> int:
        """
        0 for C_init, then 1 or 2
        """
    @property
    def iteration(self) -> int:
        """
        Index of this configuration in the plan
        """
class History:
    """
    Configurations [start, stop) of a plan as stacked arrays.
    """
    def __init__(self, *args: typing.Any, **kwargs: typing.Any) -> None:
        """Not constructible from Python: returned by Planner.history."""
    @property
    def palm_pose(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        (K, 4, 4)
        """
    @property
    def joints(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        (K, M, N+1, 3)
        """
    @property
    def angles(self) -> numpy.typing.NDArray[numpy.float64]:
        """
        (K, M, N)
        """
    @property
    def tip_state(self) -> numpy.typing.NDArray[numpy.int8]:
        """
        (K, M) int8
        """
    @property
    def phase(self) -> numpy.typing.NDArray[numpy.int8]:
        """
        (K,) int8
        """
class Planner:
    """
    The Hugger planner (docs/algorithm.md) over a simulated world.
    """
    def __init__(self, hand: HandModel, sensing: Sensing | Object, target: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], palm_pose: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], params: PlannerParams = ..., skin: str = 'section') -> None:
        ...
    def history(self, start: typing.SupportsInt | typing.SupportsIndex = 0, stop: typing.SupportsInt | typing.SupportsIndex = ...) -> History:
        """
        Configurations [start, stop) so far, as a History of stacked arrays.
        """
    def plan(self, timeout: typing.SupportsFloat | None = None) -> str:
        """
        Run to the end (GIL released); returns the status. With ``timeout`` (seconds, positive finite) the plan stops with status 'timeout' once that much wall-clock time has passed. An exception raised by the skin propagates unchanged and ends the plan (status 'error'). A signal's exception (Ctrl-C: KeyboardInterrupt) or interrupt() stops it between iterations, still running: a later call goes on (one raised inside a Python skin's callback ends it, status 'error', as any exception of the skin).
        """
    def configuration(self, k: typing.SupportsInt | typing.SupportsIndex) -> Configuration | None:
        """
        Configuration k (from 0, C_init), planning on until it exists (as step() does); None when the plan ends before it. step() goes on after it.
        """
    def interrupt(self) -> None:
        """
        Ask a plan() running in another thread to stop between iterations, raising KeyboardInterrupt there (the plan still running). Without one running, the next plan() stops at once.
        """
    @property
    def params(self) -> PlannerParams:
        """
        The parameters in force, defaults resolved
        """
    @property
    def size(self) -> int:
        ...
    @property
    def skin(self) -> str:
        """
        How the object is sensed: 'mesh', 'section', or 'custom' (a Sensing skin)
        """
    @property
    def stats(self) -> PlannerStats:
        """
        The plan's counters
        """
    @property
    def stats_json(self) -> str:
        """
        The plan's counters as the JSON a trajectory records (json.dumps of their dict)
        """
    @property
    def status(self) -> str:
        ...
class QualityResult:
    """
    Grasp-wrench-space figures of a set of contacts.
    """
    def __init__(self, *args: typing.Any, **kwargs: typing.Any) -> None:
        """Not constructible from Python: returned by grasp_quality."""
    def __repr__(self) -> str:
        ...
    @property
    def force_closure(self) -> bool:
        """
        The origin lies strictly inside the grasp wrench space.
        """
    @property
    def epsilon(self) -> float:
        """
        Ferrari-Canny epsilon: radius of the largest origin-centred ball in the GWS (0 without closure).
        """
    @property
    def volume(self) -> float:
        """
        6D volume of the GWS (0 when flat).
        """
    @property
    def wrenches(self) -> int:
        """
        Distinct primitive wrenches of the GWS.
        """
def grasp_quality(points: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], normals: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], center: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], mu: typing.SupportsFloat = 0.5, cone_edges: typing.SupportsInt = 8, torque_scale: typing.SupportsFloat = 1.0, volume: bool = True) -> QualityResult:
    """
    Force closure, epsilon and volume of the L1 grasp wrench space of contacts at points (C, 3) (m, world) with outward normals (C, 3), torques about center (3,) divided by torque_scale (m). Qhull, GIL released. volume=False skips the full hull (volume reported 0): epsilon by cutting planes.
    """

def check_pose(pose: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], name: str = 'palm_pose') -> None:
    """
    Raise ValueError, saying what is wrong, unless ``pose`` is a rigid (4, 4) transform: finite, last row (0, 0, 0, 1), rotation orthonormal with determinant +1 within RIGID_TOLERANCE (the engine's rule).
    """
def check_target(target: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], obj: typing.Any = None) -> None:
    """
    Raise ValueError, saying what is wrong, unless ``target`` is a finite point (3,) within MAX_COORDINATE of the origin, and inside ``obj`` where that is an Object (the planner's rules for T; with a skin, T is taken as given).
    """
def check_timeout(seconds: typing.Any) -> float:
    """
    ``seconds`` as a float: raise ValueError unless it is a positive finite number.
    """
def resolve_params(hand: HandModel, params: PlannerParams) -> PlannerParams:
    """
    The parameters a Planner of ``hand`` plans with, defaults resolved; ValueError for a step longer than the hand's shortest link, a contact_tolerance not below the step, an epsilon above it.
    """


#: A palm pose is rigid when |R^T R - I| and |det R - 1| are at most this (the engine's rule).
RIGID_TOLERANCE: float
#: Largest coordinate or size (m) of an object's vertex or a skin query.
MAX_COORDINATE: float
#: Largest number of fingers M and of links per finger N of a hand.
MAX_FINGERS: int
MAX_LINKS: int
#: Largest max_iterations of a plan.
MAX_ITERATIONS: int
#: The planner's contact tolerance delta (m) when none is given.
DEFAULT_CONTACT_TOLERANCE: float
#: The Phase 2 rule sets a PlannerParams accepts (docs/algorithm.md).
RULES: tuple[str, ...]
#: How a Planner senses an Object: "mesh" (3D queries) or "section" (2D per finger plane).
SKINS: tuple[str, ...]
