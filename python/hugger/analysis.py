"""Grasp analysis over *all* contacts of a configuration: the palm and every link (docs/validation.md).

Three layers, each usable on its own:

* :func:`contacts` / :func:`contacts_of` find the contacts of one hand configuration with the
  object: points on the object's surface, outward normals, which finger and link (or the palm)
  each belongs to, and the gap. numpy only.
* :func:`wrap_angle` says how far each finger's contacts wrap around the target T. numpy only.
* :func:`escape_distance` says how far the object can slide away from the hand, held fixed, in
  directions all around: a caging figure. numpy only.
* :func:`grasp_quality` builds the grasp wrench space of a set of contacts and reports force
  closure, the Ferrari-Canny epsilon and the hull volume (Qhull, in the compiled core). numpy only.

:func:`analyze` runs all three on a trajectory's configuration and returns plain JSON types; the
CLI's ``--json`` output and the README tables are made from it.

Units are metres and degrees (wrap angles) in the world frame; signed gaps are negative when the
hand penetrates the object (FCL's convention, docs/model.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, cast

import numpy as np

from . import _core, _stable
from ._checks import flag, positive, whole
from ._types import CONTACT_DISTANCE

if TYPE_CHECKING:
    from .hand import Hand

__all__ = [
    "Contacts",
    "Quality",
    "analyze",
    "contacts",
    "contacts_of",
    "escape",
    "escape_distance",
    "grasp_quality",
    "primitive_wrenches",
    "wrap_angle",
]

_PALM = -1
#: Sample spacing cap (m) along link axes and over the palm.
_MAX_SPACING = 1e-3
#: At most this many samples per link axis (bounds the cost for huge, thin links).
_MAX_LINK_SAMPLES = 400
#: The palm's samples at least this fraction of its radius or thickness, the larger, apart: at
#: most about 128 rings and rim levels (bounds the cost for a huge palm, or a hand in millimetres).
_MAX_PALM_RINGS = 128
#: At most this many representative contacts from the palm's touching region.
_PALM_CONTACTS = 8
#: :func:`escape_distance` slides the object this far at most (m): the hold test's limit on how
#: far a held object may move (docs/validation.md).
ESCAPE_REACH = 0.05
#: :func:`escape_distance`'s sample spacing along each direction (m).
ESCAPE_STEP = 0.002
#: A hand part penetrating the slid object by more than this (m) blocks the slide.
_ESCAPE_PENETRATION = 1e-4
#: At most this many samples per direction in :func:`escape_distance`.
_MAX_ESCAPE_SAMPLES = 10000


# --------------------------------------------------------------------------------------------
# Contacts
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Contacts:
    """The contacts of one hand configuration with the object, in the world frame (m).

    Rows are ordered: palm contacts first, then finger by finger (0..M-1), link by link from the
    root (0..N-1), and along each link from its tail joint toward its tip.
    """

    points: np.ndarray  #: (C, 3) contact points on the object's surface (m, world frame)
    normals: np.ndarray  #: (C, 3) outward unit normals of the object at ``points``
    finger: np.ndarray  #: (C,) int finger index m, -1 for the palm
    link: np.ndarray  #: (C,) int link index n, -1 for the palm
    gap: np.ndarray  #: (C,) signed gap (m) between the hand's surface and the object there; < 0 penetrates
    num_fingers: int = 0  #: M, the hand's number of fingers (for :meth:`per_finger`)
    num_links: int = 0  #: N, links per finger

    def __post_init__(self) -> None:
        for name, dtype in (("points", np.float64), ("normals", np.float64), ("finger", np.int64),
                            ("link", np.int64), ("gap", np.float64)):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=dtype))
        c = self.points.shape[0] if self.points.ndim else 0
        if self.points.shape != (c, 3) or self.normals.shape != (c, 3):
            raise ValueError(f"points and normals must be (C, 3), got {self.points.shape} and {self.normals.shape}")
        for name in ("finger", "link", "gap"):
            if getattr(self, name).shape != (c,):
                raise ValueError(f"{name} must be ({c},), got {getattr(self, name).shape}")

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def per_finger(self) -> np.ndarray:
        """(M,) int: how many links of each finger are in contact."""
        m = max(int(self.num_fingers), int(self.finger.max()) + 1 if len(self) else 0)
        pairs = {(int(f), int(n)) for f, n in zip(self.finger, self.link) if f >= 0}
        counts = np.zeros(m, dtype=np.int64)
        for f, _ in pairs:
            counts[f] += 1
        return counts

    @property
    def links_in_contact(self) -> int:
        """Number of distinct links (over all fingers) with at least one contact."""
        return int(self.per_finger().sum())

    @property
    def palm_contact(self) -> bool:
        """Whether the palm touches the object."""
        return bool(np.any(self.finger == _PALM))

    @classmethod
    def from_arrays(cls, points: Any, normals: Any, finger: Any = None, link: Any = None, gap: Any = None,
                    num_fingers: int = 0, num_links: int = 0) -> Contacts:
        """Contacts from plain arrays (e.g. a hand-made grasp): ``points`` and ``normals`` (C, 3),
        normals outward and normalised here; ``finger``/``link`` default to 0..C-1 / 0, ``gap`` to 0."""
        p = np.asarray(points, dtype=np.float64)
        n = np.asarray(normals, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3 or n.shape != p.shape:
            raise ValueError(f"points and normals must both be (C, 3), got {p.shape} and {n.shape}")
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(n))):
            raise ValueError("points and normals must be finite")
        length = _stable.norm(n)
        if np.any(length < 1e-12):
            raise ValueError("normals must be non-zero")
        c = p.shape[0]
        f = np.arange(c) if finger is None else np.asarray(finger).reshape(-1)
        ln = np.zeros(c, dtype=np.int64) if link is None else np.asarray(link).reshape(-1)
        g = np.zeros(c) if gap is None else np.asarray(gap, dtype=np.float64).reshape(-1)
        return cls(points=p, normals=n / length[:, None], finger=f.astype(np.int64), link=ln.astype(np.int64),
                   gap=g, num_fingers=int(num_fingers), num_links=int(num_links))


def _trajectory_index(traj: Any, k: int) -> int:
    from .trajectory import Trajectory, configuration_index

    if not isinstance(traj, Trajectory):
        raise ValueError(f"traj must be a hugger.Trajectory, got {type(traj).__name__}")
    return configuration_index(len(traj), k)


def _link_spacing(radius: float, length: float) -> float:
    """Sample spacing (m) along a link axis: r/4 or 1 mm, whichever is smaller (1 mm when r = 0)."""
    h = _MAX_SPACING if radius <= 0 else min(radius / 4.0, _MAX_SPACING)
    return max(h, length / _MAX_LINK_SAMPLES)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) index of every run of True in a 1D bool array."""
    if not mask.any():
        return []
    d = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1
    return list(zip(starts.tolist(), ends.tolist()))


def _golden_min(fun: Callable[[float], float], lo: float, hi: float, iterations: int = 48) -> float:
    """Argmin of a (locally unimodal) scalar function on [lo, hi]."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = lo, hi
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = fun(c), fun(d)
    for _ in range(iterations):
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = fun(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = fun(d)
    return c if fc <= fd else d


def _axis_samples(a: np.ndarray, b: np.ndarray, radius: float, links: list[int]) -> tuple[list[np.ndarray], np.ndarray]:
    """The axes [a_i, b_i] of ``links`` sampled every :func:`_link_spacing`: each link's sample
    parameters (0 to 1), and all the sample points (k, 3), link after link."""
    ts = []
    for i in links:
        length = float(_stable.norm(b[i] - a[i]))
        ts.append(np.linspace(0.0, 1.0, max(2, int(math.ceil(length / _link_spacing(radius, length))) + 1)))
    owner = np.repeat(np.asarray(links, dtype=np.int64), [t.size for t in ts])
    t = np.concatenate(ts)
    return ts, a[owner] + t[:, None] * (b[owner] - a[owner])


def _palm_points(pose: np.ndarray, radius: float, thickness: float) -> tuple[np.ndarray, np.ndarray]:
    """The palm's front face and rim sampled (:func:`_palm_samples`, spacing min(1 mm, radius/8,
    thickness/2), but at least max(radius, thickness)/128): the points in the palm frame and in
    the world."""
    spacing = max(min(_MAX_SPACING, radius / 8.0, thickness / 2.0), max(radius, thickness) / _MAX_PALM_RINGS)
    local = _palm_samples(radius, thickness, spacing)
    return local, _stable.matmul(local, pose[:3, :3].T) + pose[:3, 3]


def _link_contacts(obj: Any, joints: np.ndarray, radius: float, distance: float) -> list[tuple[int, int, np.ndarray]]:
    """Per link in contact, the sample points (k, 3) on its axis whose surface points are emitted."""
    n1 = joints.shape[1]
    a, b = joints[:, :-1].reshape(-1, 3), joints[:, 1:].reshape(-1, 3)
    gaps = obj.segment_distance(a, b) - radius
    touching = np.flatnonzero(gaps <= distance)
    if touching.size == 0:
        return []
    # Sample every touching link's axis densely, all in one query.
    ts, samples = _axis_samples(a, b, radius, touching.tolist())
    sample_gap = obj.closest(samples)["distance"] - radius
    out = []
    start = 0
    for i, tt in zip(touching.tolist(), ts):
        sl = slice(start, start + tt.size)
        start += tt.size
        runs = _runs(sample_gap[sl] <= distance)
        if runs:
            idx = sorted({j for run in runs for j in run})
            pts = samples[sl][idx]
        else:
            # The segment comes within reach between two samples: find its nearest axis point.
            j = int(np.argmin(sample_gap[sl]))
            lo, hi = tt[max(j - 1, 0)], tt[min(j + 1, tt.size - 1)]
            fun = lambda s, i=i: float(obj.closest((a[i] + s * (b[i] - a[i]))[None])["distance"][0])  # noqa: E731
            s = _golden_min(fun, float(lo), float(hi))
            pts = (a[i] + s * (b[i] - a[i]))[None]
        out.append((i // (n1 - 1), i % (n1 - 1), pts))
    return out


def _palm_samples(radius: float, thickness: float, spacing: float) -> np.ndarray:
    """Points (k, 3) in the palm frame P on the front face disc (z = 0) and on the rim (z in [-t, 0])."""
    pts = [np.zeros((1, 3))]
    rings = max(1, int(math.ceil(radius / spacing)))
    for i in range(1, rings + 1):
        rho = radius * i / rings
        count = max(6, int(math.ceil(2 * math.pi * rho / spacing)))
        ang = 2 * math.pi * np.arange(count) / count
        pts.append(np.column_stack([rho * _stable.cos(ang), rho * _stable.sin(ang), np.zeros(count)]))
    count = max(6, int(math.ceil(2 * math.pi * radius / spacing)))
    ang = 2 * math.pi * np.arange(count) / count
    levels = max(1, int(math.ceil(thickness / spacing)))
    for z in -thickness * np.arange(1, levels + 1) / levels:
        pts.append(np.column_stack([radius * _stable.cos(ang), radius * _stable.sin(ang), np.full(count, z)]))
    return np.concatenate(pts)


def _project_to_palm(q: np.ndarray, radius: float, thickness: float) -> np.ndarray:
    """Nearest point of the solid palm cylinder (palm frame) to the point q (palm frame)."""
    p = q.copy()
    rho = math.hypot(p[0], p[1])
    if rho > radius:
        p[:2] *= radius / rho
    p[2] = min(0.0, max(-thickness, p[2]))
    return p


def _palm_contacts(obj: Any, palm_pose: np.ndarray, radius: float, thickness: float,
                   distance: float) -> np.ndarray:
    """Palm-surface points (k <= 8, 3) in the world whose nearest surface points are emitted."""
    gap = float(obj._core.palm_gap(palm_pose, radius, thickness))
    if gap > distance:
        return np.zeros((0, 3))
    rot, origin = palm_pose[:3, :3], palm_pose[:3, 3]
    local, world = _palm_points(palm_pose, radius, thickness)
    d = obj.closest(world, max_distance=distance)["distance"]  # only the touching samples matter
    touching = np.flatnonzero(d <= distance)
    if touching.size == 0:
        d = obj.closest(world)["distance"]
        # The palm comes within reach between samples: alternate nearest-point projections
        # (object <- palm <- object ...) from the best sample to the nearest pair.
        p = local[int(np.argmin(d))]
        for _ in range(40):
            q = obj.closest((_stable.matmul(p, rot.T) + origin)[None])["point"][0]
            p_new = _project_to_palm(_stable.matmul(q - origin, rot), radius, thickness)
            if float(_stable.norm(p_new - p)) < 1e-10:
                p = p_new
                break
            p = p_new
        return cast(np.ndarray, (_stable.matmul(p, rot.T) + origin)[None])
    sel = local[touching]
    ang = 2 * math.pi * np.arange(_PALM_CONTACTS) / _PALM_CONTACTS
    proj = _stable.matmul(sel[:, :2], np.stack([_stable.cos(ang), _stable.sin(ang)]))
    extreme = sorted(set(np.argmax(proj, axis=0).tolist()))
    return world[touching[extreme]]


def _configuration(hand: dict[str, Any] | Hand, obj: Any, palm_pose: Any, joints: Any
                   ) -> tuple[int, int, float, float, float, np.ndarray, np.ndarray]:
    """The checked arguments of a configuration's analysis: fingers M, links N, link radius, palm
    radius and thickness, the palm pose and the (M, N+1, 3) joints, as arrays."""
    from .world import Object

    if not isinstance(obj, Object):
        raise ValueError(f"obj must be a hugger.Object, got {type(obj).__name__}")
    if hasattr(hand, "to_dict"):  # a hugger.Hand
        hand = hand.to_dict()
    try:
        m, n = int(hand["fingers"]), int(hand["links"])
        radius = float(hand["link_radius"])
        palm_radius, palm_thickness = float(hand["palm_radius"]), float(hand["palm_thickness"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"hand must be a hand dict (Hand.to_dict()), missing or bad entry: {exc}") from None
    if not (radius >= 0 and palm_radius > 0 and palm_thickness > 0 and
            all(map(math.isfinite, (radius, palm_radius, palm_thickness)))):
        raise ValueError("hand sizes must be finite, link_radius >= 0, palm_radius and palm_thickness > 0")
    pose = np.asarray(palm_pose, dtype=np.float64)
    _core.check_pose(pose)  # the engine's rule: a rigid (4, 4) transform
    j = np.asarray(joints, dtype=np.float64)
    if j.shape != (m, n + 1, 3):
        raise ValueError(f"joints must be (M, N+1, 3) = ({m}, {n + 1}, 3), got {j.shape}")
    if not np.all(np.isfinite(j)):
        raise ValueError("joints must be finite")
    return m, n, radius, palm_radius, palm_thickness, pose, j


def contacts_of(hand: dict[str, Any] | Hand, obj: Any, palm_pose: Any, joints: Any,
                distance: float = CONTACT_DISTANCE) -> Contacts:
    """All contacts of a hand configuration with ``obj`` (a :class:`hugger.Object`).

    ``hand`` is the hand as a dict (``Hand.to_dict()`` or ``Trajectory.hand``) or a
    :class:`hugger.Hand`, ``palm_pose`` the
    palm pose T_WP (4, 4), ``joints`` the joint positions (M, N+1, 3) in the world (m).

    *Links.* Link n of finger m is a capsule of radius r = ``hand["link_radius"]`` about the axis
    segment joints[m, n] -> joints[m, n+1]. It is in contact when its axis comes within
    r + ``distance`` of the surface (the same test as :meth:`Trajectory.link_gaps`). Its axis is
    sampled every min(r/4, 1 mm) (1 mm when r = 0; at most 400 samples); for every run of samples
    within r + ``distance`` the surface points nearest the run's first and last samples are
    contacts (one point for a one-sample run). A link in contact whose samples all miss (the
    nearest approach falls between samples) gets one contact at its axis point nearest the surface.

    *Palm.* A solid cylinder of ``palm_radius`` and ``palm_thickness`` whose front face is centred
    at the palm pose origin with normal the pose's local z, its body behind (local z in [-t, 0]),
    as in docs/model.md and :meth:`Trajectory.palm_gap`. When its gap is within ``distance``,
    its front face disc and rim are sampled (spacing min(1 mm, radius/8, thickness/2)) and the
    surface points nearest the touching region's extreme samples in 8 in-plane directions are
    contacts (at most 8, fewer when they coincide).

    ``gap`` is the signed distance from the sample on the hand's surface (link axis point minus
    r, or palm surface point) to the object; negative when penetrating.
    """
    m, n, radius, palm_radius, palm_thickness, pose, j = _configuration(hand, obj, palm_pose, joints)
    dist = positive("distance", distance, allow_zero=True)

    sources: list[tuple[int, int, np.ndarray, float]] = []  # finger, link, hand-surface samples, radius
    palm = _palm_contacts(obj, pose, palm_radius, palm_thickness, dist)
    if len(palm):
        sources.append((_PALM, _PALM, palm, 0.0))
    for f, ln, pts in _link_contacts(obj, j, radius, dist):
        sources.append((f, ln, pts, radius))
    if not sources:
        empty = np.zeros((0, 3))
        return Contacts(empty, empty.copy(), np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0),
                        num_fingers=m, num_links=n)
    samples = np.concatenate([s[2] for s in sources])
    near = obj.closest(samples)
    offset = np.concatenate([np.full(len(s[2]), s[3]) for s in sources])
    finger = np.concatenate([np.full(len(s[2]), s[0], dtype=np.int64) for s in sources])
    link = np.concatenate([np.full(len(s[2]), s[1], dtype=np.int64) for s in sources])
    normals = np.asarray(near["normal"], dtype=np.float64)
    normals = normals / _stable.norm(normals)[:, None]
    return Contacts(points=np.asarray(near["point"], dtype=np.float64), normals=normals, finger=finger,
                    link=link, gap=np.asarray(near["distance"], dtype=np.float64) - offset,
                    num_fingers=m, num_links=n)


def collision_tolerance(link_radius: float) -> float:
    """The independent checker's collision tolerance (m) for links of ``link_radius``: a hand part
    deeper in the object fails it (docs/validation.md)."""
    return max(0.02 * float(link_radius), 5e-5)


def penetration(traj: Any, k: int = -1, obj: Any = None) -> float:
    """How deep (m) the hand lies inside the object at configuration ``k`` of a
    :class:`hugger.Trajectory`, at its deepest point; 0 when it does not. Every link's axis is
    sampled as :func:`contacts_of` samples it (every min(r/4, 1 mm)), all of it and not only
    where it touches (a link may pass through the object between its contacts), and so are the
    palm's front face and rim; a point's depth is its signed distance to the surface less the
    link radius (negative inside)."""
    k = _trajectory_index(traj, k)
    obj = obj if obj is not None else traj.object()
    _, _, radius, palm_radius, palm_thickness, pose, j = _configuration(traj.hand, obj, traj.palm_pose[k], traj.joints[k])
    a, b = j[:, :-1].reshape(-1, 3), j[:, 1:].reshape(-1, 3)
    _, axis = _axis_samples(a, b, radius, list(range(len(a))))
    _, palm = _palm_points(pose, palm_radius, palm_thickness)
    d = obj.signed_distance(np.concatenate([axis, palm]))  # one query: links less their radius, the palm
    return max(0.0, float(np.max(np.concatenate([radius - d[:len(axis)], -d[len(axis):]]))))


def contacts(traj: Any, k: int = -1, distance: float = CONTACT_DISTANCE, obj: Any = None) -> Contacts:
    """All contacts (palm and every link) of configuration ``k`` of a :class:`hugger.Trajectory`.

    ``distance`` (m) is the contact distance: a link or the palm is in contact when its surface
    comes within ``distance`` of the object (as in :meth:`Trajectory.summary`). ``obj`` may pass the
    trajectory's object, already built, to save rebuilding it. See :func:`contacts_of`.
    """
    k = _trajectory_index(traj, k)
    obj = traj.object() if obj is None else obj
    return contacts_of(traj.hand, obj, traj.palm_pose[k], traj.joints[k], distance)


def escape_distance(hand: dict[str, Any] | Hand, obj: Any, palm_pose: Any, joints: Any, directions: int = 26,
                    reach: float = ESCAPE_REACH, step: float = ESCAPE_STEP) -> np.ndarray:
    """How far (m) the object can slide away from the hand, held fixed, in each of ``directions``
    directions spread evenly over the sphere (:func:`hugger.approach_directions`): a caging figure.

    The object is translated by t along each direction, t = ``step``, 2 ``step``, ... and
    ``reach`` last; the slide is blocked at the first t where a link capsule (as in
    :func:`contacts_of`) penetrates the moved object by more than 0.1 mm or its axis crosses the
    surface (so links of radius 0 block too), or the palm touches into it at all (its gap is
    signed only to touching). Returns ``(directions,)`` distances: that first blocked t, or
    ``inf`` where the object slides the whole ``reach`` freely. A grasp that cages the object has
    small distances in every direction; a grasp that holds it by friction alone has a free
    direction. Sampled: a part thinner than ``step`` may be passed between two samples; at most
    10,000 samples per direction. ``hand``, ``palm_pose`` and ``joints`` are as in
    :func:`contacts_of`.
    """
    from .search import _direction_count, approach_directions

    _, _, radius, palm_radius, palm_thickness, pose, j = _configuration(hand, obj, palm_pose, joints)
    reach = positive("reach", reach)
    step = positive("step", step)
    samples = int(math.ceil(reach / step - 1e-9))
    if samples > _MAX_ESCAPE_SAMPLES:
        raise ValueError(f"reach / step must be at most {_MAX_ESCAPE_SAMPLES} samples, got {reach} / {step}")
    dirs = approach_directions(_direction_count("directions", directions))
    a, b = j[:, :-1].reshape(-1, 3), j[:, 1:].reshape(-1, 3)
    out = np.full(len(dirs), np.inf)
    alive = np.arange(len(dirs))  # the directions still sliding freely
    for i in range(1, samples + 1):
        t = min(i * step, reach)
        shift = -t * dirs[alive]  # moving the object by +t d is moving the hand by -t d
        axis = obj.segment_distance((a[None] + shift[:, None]).reshape(-1, 3),
                                    (b[None] + shift[:, None]).reshape(-1, 3)).reshape(len(alive), len(a))
        blocked = ((axis < 0.0) | (axis - radius < -_ESCAPE_PENETRATION)).any(axis=1)
        for k in np.flatnonzero(~blocked):
            moved = pose.copy()
            moved[:3, 3] += shift[k]
            blocked[k] = obj._core.palm_gap(moved, palm_radius, palm_thickness) < 0.0  # signed to touching only
        out[alive[blocked]] = t
        alive = alive[~blocked]
        if not len(alive):
            break
    return out


def escape(hand: dict[str, Any] | Hand, obj: Any, palm_pose: Any, joints: Any) -> float:
    """The search's *escape* (m): the largest of :func:`escape_distance`'s distances with its
    defaults, at most ``ESCAPE_REACH`` (a free direction counts as the reach)."""
    return float(min(escape_distance(hand, obj, palm_pose, joints).max(), ESCAPE_REACH))


# --------------------------------------------------------------------------------------------
# Wrap angle
# --------------------------------------------------------------------------------------------

def _finger_angles(hand: dict[str, Any]) -> np.ndarray:
    m = int(hand["fingers"])
    phi = hand.get("finger_angles")
    return np.asarray(phi, dtype=np.float64) if phi is not None else 2 * np.pi * np.arange(m) / m


def wrap_angle(traj: Any, k: int = -1, distance: float = CONTACT_DISTANCE, obj: Any = None,
               found: Contacts | None = None) -> np.ndarray:
    """(M,) degrees: how far each finger's contacts wrap around the target T in its finger plane.

    For finger m, each of its contact points (links only, not the palm) is projected onto the
    finger plane Pi_m (docs/model.md: through the root R_m, spanned by the radial direction
    u_m and the palm normal p) and given its polar angle about T (projected onto Pi_m) in the
    in-plane coordinates (xi along u_m, eta along p). Walking the finger's contacts in order, root
    to tip, the angles are unwrapped (consecutive contacts differ by less than 180 degrees); the
    wrap angle is the largest minus the smallest unwrapped angle: the angle about T swept by the
    finger's contacts. A finger with fewer than two contacts wraps 0 degrees. A finger lying
    along a sphere of centre T from its pole to its equator wraps 90 degrees.

    ``found`` may pass the contacts of configuration k already computed by :func:`contacts`.
    """
    k = _trajectory_index(traj, k)
    found = contacts(traj, k, distance, obj) if found is None else found
    hand = traj.hand
    m = int(hand["fingers"])
    pose = np.asarray(traj.palm_pose[k], dtype=np.float64)
    phi = _finger_angles(hand)
    target = np.asarray(traj.target, dtype=np.float64)
    out = np.zeros(m)
    for f in range(m):
        sel = found.finger == f
        if np.count_nonzero(sel) < 2:
            continue
        u = _stable.matmul(pose[:3, :3], np.array([math.cos(phi[f]), math.sin(phi[f]), 0.0]))
        p = pose[:3, 2]
        rel = found.points[sel] - target
        ang = np.unwrap(_stable.arctan2(_stable.matmul(rel, p), _stable.matmul(rel, u)))
        out[f] = math.degrees(float(ang.max() - ang.min()))
    return out


# --------------------------------------------------------------------------------------------
# Grasp wrench space
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Quality:
    """Grasp-wrench-space figures of a set of contacts (see :func:`grasp_quality`)."""

    force_closure: bool  #: the origin lies strictly inside the grasp wrench space
    epsilon: float  #: Ferrari-Canny epsilon: radius of the largest origin-centred ball in the GWS (0 if none)
    volume: float  #: 6D volume of the GWS (0 when it is flat)
    torque_scale: float  #: length (m) the torques were divided by
    wrenches: int  #: number of distinct primitive contact wrenches the GWS is the hull of


def _tangents(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tangent bases (C, 3), (C, 3) of unit vectors n (C, 3): t1 = n x e_k / |.|, e_k the world axis
    least aligned with n (lowest index on ties), t2 = n x t1."""
    axis = np.argmin(np.abs(n), axis=1)
    e = np.eye(3)[axis]
    t1 = np.cross(n, e)
    t1 /= _stable.norm(t1)[:, None]
    return t1, np.cross(n, t1)


def primitive_wrenches(points: Any, normals: Any, center: Any, mu: float, cone_edges: int,
                       torque_scale: float) -> np.ndarray:
    """(C * E, 6) primitive contact wrenches (f, tau / torque_scale), E = ``cone_edges`` (1 when mu = 0).

    Contact i at ``points[i]`` (m, world) pushes into the object along d = -normals[i] with unit
    normal force; its friction cone is linearised by the E edges d + mu (cos a_j t1 + sin a_j t2),
    a_j = 2 pi j / E, with t1 = d x e_k / |d x e_k|, e_k the world axis least aligned with d
    (lowest index on ties), and t2 = d x t1. tau = (points[i] - center) x f, divided by
    ``torque_scale`` (m). Rows are contact-major: row i * E + j is edge j of contact i.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    d = -np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    if d.shape != p.shape:
        raise ValueError(f"points and normals must both be (C, 3), got {p.shape} and {d.shape}")
    if not (float(torque_scale) > 0) or float(mu) < 0 or int(cone_edges) < 3:
        raise ValueError("need torque_scale > 0, mu >= 0 and cone_edges >= 3")
    d = d / _stable.norm(d)[:, None]
    c = np.asarray(center, dtype=np.float64).reshape(3)
    if mu == 0:
        forces = d[:, None, :]
    else:
        t1, t2 = _tangents(d)
        a = 2 * np.pi * np.arange(cone_edges) / cone_edges
        tangent = _stable.cos(a)[None, :, None] * t1[:, None, :] + _stable.sin(a)[None, :, None] * t2[:, None, :]
        forces = d[:, None, :] + mu * tangent
    arms = np.broadcast_to((p - c)[:, None, :], forces.shape)
    torques = np.cross(arms, forces) / torque_scale
    return np.concatenate([forces, torques], axis=2).reshape(-1, 6)


def grasp_quality(contacts: Contacts, center: Any, mu: float = 0.5, cone_edges: int = 8,
                  torque_scale: float | None = None, obj: Any = None, volume: bool = True) -> Quality:
    """Force closure, Ferrari-Canny epsilon and volume of the L1 grasp wrench space of ``contacts``.

    Every contact pushes into the object (along -normal) with a unit normal force and Coulomb
    friction ``mu``, its cone linearised by ``cone_edges`` edges (:func:`primitive_wrenches`; the
    cone's turn about the normal is fixed by a world-axis rule, so with mu > 0 the figures change
    slightly, within the linearisation, when the grasp is rotated). The grasp wrench space (GWS) is
    the convex hull, in R^6, of all the contacts' primitive wrenches (f, tau / torque_scale) with
    torques about ``center`` (3,) (m, world). ``epsilon`` is the radius of the largest ball about
    the origin inside the GWS (0 when the origin is not strictly inside: no force closure);
    ``volume`` is the GWS's 6D volume. An epsilon below 1e-9 of the largest wrench coordinate
    counts as 0 (the origin on the boundary is not force closure). Flat or degenerate wrench
    sets (too few contacts, all torques zero, ...) give no force closure, epsilon 0, volume 0.

    ``torque_scale`` (m) makes torques comparable with forces. Default, as in GraspIt!: the
    object's largest distance from ``center`` (its vertices' when ``obj`` is given, otherwise the
    contacts' largest distance from ``center``). Scaling the grasp and the torque scale together
    leaves every figure unchanged.

    Computed in C++ with Qhull (reentrant, fixed joggle seed: deterministic on any thread; the GIL
    is released). Coincident wrenches (agreeing to 1e-10) are kept once first. The volume needs the
    whole 6D hull, tens of thousands of facets for a hugging grasp (~0.1 s). With ``volume=False``
    the volume is reported as 0 and epsilon comes from a small hull grown only where it decides
    (cutting planes: the facet nearest the origin is checked against every wrench, the wrench
    furthest beyond it added, until none is; about 1-10 ms): the same epsilon and force closure.
    """
    if not isinstance(contacts, Contacts):
        raise ValueError(f"contacts must be hugger.analysis.Contacts, got {type(contacts).__name__}")
    if not (np.all(np.isfinite(contacts.points)) and np.all(np.isfinite(contacts.normals))):
        raise ValueError("contact points and normals must be finite")
    c = np.asarray(center, dtype=np.float64)
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ValueError(f"center must be a finite 3-vector (m), got {center!r}")
    mu_f = positive("mu", mu, allow_zero=True)
    cone_edges = whole("cone_edges", cone_edges, 3, 64)
    volume = flag("volume", volume)
    if torque_scale is None:
        if obj is not None:
            torque_scale = _stable.farthest(obj.vertices, c)
        else:
            torque_scale = _stable.farthest(contacts.points, c) if len(contacts) else 1.0
    scale = positive("torque_scale", torque_scale)
    r = _core.grasp_quality(contacts.points.reshape(-1, 3), contacts.normals.reshape(-1, 3), c, mu_f,
                            int(cone_edges), scale, bool(volume))
    return Quality(force_closure=bool(r.force_closure), epsilon=float(r.epsilon), volume=float(r.volume),
                   torque_scale=scale, wrenches=int(r.wrenches))


# --------------------------------------------------------------------------------------------
# Everything at once
# --------------------------------------------------------------------------------------------

def analyze(traj: Any, k: int = -1, mu: float = 0.5, distance: float = CONTACT_DISTANCE, cone_edges: int = 8,
            obj: Any = None, volume: bool = True) -> dict[str, Any]:
    """The grasp of configuration ``k`` of ``traj`` judged over all its contacts, as plain JSON types.

    Keys: ``contacts`` (number of contact points), ``links_in_contact``, ``links`` (M * N),
    ``palm_contact``, ``per_finger_contacts`` (links in contact per finger), ``wrap_angle_deg``
    (per finger, :func:`wrap_angle`), ``force_closure``, ``epsilon``, ``volume``
    (:func:`grasp_quality` with torques about T, torque scale the object's largest distance
    from T), ``mu``, ``torque_scale_m``, ``penetration_m`` (:func:`penetration`: how deep the hand
    lies inside the object, 0 when it does not: a contact counts however deep,
    so a hand sunk into an object, of another tool's plan or one rescaled since, would otherwise
    look like a firm grasp). ``volume=False`` skips the GWS volume (reported as 0),
    the costly part (see :func:`grasp_quality`).
    """
    k = _trajectory_index(traj, k)
    obj = obj if obj is not None else traj.object()
    found = contacts(traj, k, distance, obj)
    target = np.asarray(traj.target, dtype=np.float64)
    q = grasp_quality(found, target, mu=mu, cone_edges=cone_edges, obj=obj, volume=volume)
    hand = traj.hand
    return {
        "contacts": len(found),
        "links_in_contact": found.links_in_contact,
        "links": int(hand["fingers"]) * int(hand["links"]),
        "palm_contact": found.palm_contact,
        "per_finger_contacts": [int(x) for x in found.per_finger()],
        "wrap_angle_deg": [float(x) for x in wrap_angle(traj, k, distance, obj, found)],
        "force_closure": q.force_closure,
        "epsilon": q.epsilon,
        "volume": q.volume,
        "mu": float(mu),
        "torque_scale_m": q.torque_scale,
        "penetration_m": penetration(traj, k, obj),
    }
