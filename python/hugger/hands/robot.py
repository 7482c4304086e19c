"""Hands from robot description files (URDF through yourdfpy, MJCF through MuJoCo) and back.

Both importers reduce the file to finger chains in the palm frame at the reference
configuration (every joint at 0, the joints named in ``fixed_joints`` at their given values):
per finger its revolute joints (name, anchor point, axis, limits) and its fingertip. A chain
becomes a hugger finger when it is planar with its plane containing the palm normal (the palm
link's z axis): every joint axis parallel to the first and normal to z, every anchor and the tip
in the plane through the first anchor normal to that axis. The reference configuration is the
finger's rest (FROZEN) pose; a joint value q maps to the hugger angle theta = rest + q (or rest
- q where an axis points the other way).
"""
from __future__ import annotations

import logging
import math
import os
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, cast

import numpy as np

from .._checks import number, shown
from .._signals import kept
from .._rotation import axis_angle
from .. import _stable
from ..hand import Hand, rim_directions

#: Planarity tolerance: metres for points off the finger plane, and sine of the angle for axes.
PLANAR_TOLERANCE = 1e-6


@dataclass
class _Chain:
    joints: list[str] = field(default_factory=list)
    anchors: list[np.ndarray] = field(default_factory=list)  # palm frame
    axes: list[np.ndarray] = field(default_factory=list)     # palm frame, unit
    limits: list[tuple[float, float]] = field(default_factory=list)
    tip: np.ndarray | None = None
    radii: list[float] = field(default_factory=list)


def _need(module: str, user: str = "reading robot files") -> Any:
    try:
        with kept():  # (yourdfpy imports trimesh, which swallows an interrupt while it imports)
            return __import__(module)
    except ImportError:
        raise ImportError(f"{user} needs {module}: pip install 'hugger[hands]'") from None


#: The root element of each kind of robot file this module reads.
ROOTS = {"URDF": "robot", "MJCF": "mujoco"}
#: The keyword that chooses the palm, in each kind's reader.
PALM_KEYWORDS = {"URDF": "palm_link", "MJCF": "palm_body"}


def kind_of_root(tag: str) -> str | None:
    """The kind of robot file (URDF or MJCF) whose root element is ``tag``, or None."""
    return next((kind for kind, root in ROOTS.items() if root == tag), None)


class _Found(Exception):
    """The root element's start: the end of xml_root's reading."""


def xml_root(source: str, kind: str = "hand file") -> str | None:
    """The root element's tag of the XML file ``source``, read only up to that element's start;
    None where the file is not well-formed before it. ValueError, in one line, where the file
    cannot be read or declares entities (robot files have no use for them; refused before any is
    expanded). ``kind`` names the file in the messages."""
    import xml.parsers.expat as expat

    tag: list[str] = []

    def start(name: str, _attributes: Any) -> None:
        tag.append(name)
        raise _Found

    def entity(name: str, *_rest: Any) -> None:
        raise ValueError(f"{source}: declares the XML entity {name!r}; a {kind} needs none")

    parser = expat.ParserCreate()
    parser.StartElementHandler = start
    parser.EntityDeclHandler = entity
    try:
        with open(source, "rb") as fh:
            while True:
                chunk = fh.read(1 << 16)
                parser.Parse(chunk, not chunk)
                if not chunk:
                    return None
    except _Found:
        return tag[0]
    except OSError as exc:
        raise ValueError(f"{source}: cannot read the {kind} ({exc})") from None
    except expat.ExpatError:
        return None


def _check_root(source: str, kind: str) -> None:
    """Refuse a file of the other kind (URDF or MJCF) or of neither, by its root element: MuJoCo
    compiles a URDF as well as an MJCF, and would then report some missing part, not the file's
    kind. A file that is not well-formed before its root element is left to the reader."""
    tag = xml_root(source, kind)
    if tag is None or tag == ROOTS[kind]:
        return
    other = kind_of_root(tag)
    if other is None:
        raise ValueError(f"{source}: not a {kind} file: its root element is <{tag}>, not <{ROOTS[kind]}>")
    raise ValueError(f"{source}: {'an' if other == 'MJCF' else 'a'} {other} file (<{tag}> at its root), not "
                     f"{kind}: read it with hugger.Hand.from_{other.lower()} or hugger.hands.load")


class _Complaints(logging.Handler):
    """The error messages a library logs while it reads a file, held instead of printed."""

    def __init__(self, logger: str) -> None:
        super().__init__(logging.ERROR)
        self.messages: list[str] = []
        self._logger = logging.getLogger(logger)

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(" ".join(record.getMessage().split()))

    def __enter__(self) -> _Complaints:
        self._propagate = self._logger.propagate
        self._logger.addHandler(self)
        self._logger.propagate = False
        return self

    def __exit__(self, *exc: Any) -> None:
        self._logger.removeHandler(self)
        self._logger.propagate = self._propagate


_EMBED = "hugger-hand "


def _after_declaration(text: str, comment: str) -> str:
    """``text`` (XML) with ``comment`` inserted after its XML declaration (first if it has none)."""
    head, sep, rest = text.partition("?>")
    return head + sep + "\n" + comment + rest.lstrip("\n") if sep and head.lstrip().startswith("<?xml") else comment + text


def _embed(text: str, hand: Hand) -> str:
    """``text`` (XML) with the hand's exact description as a comment after the XML declaration."""
    return _after_declaration(text, f"<!-- {_EMBED}{hand.to_json()} -->\n")


def _exact(source: str, hand: Hand) -> Hand:
    """The hand embedded by to_urdf / to_mjcf in ``source`` when it agrees with ``hand`` (read from
    the file's geometry) within 1e-9 m / rad: the same numbers bit for bit, so that a round trip
    plans identically. Otherwise (no comment, or the file was edited) ``hand`` itself."""
    import json
    try:
        with open(source, encoding="utf-8") as fh:
            text = fh.read(1 << 20)
    except OSError:
        return hand
    start = text.find("<!-- " + _EMBED)
    if start < 0:
        return hand
    end = text.find("-->", start)
    try:
        embedded = Hand.from_dict(json.loads(text[start + 5 + len(_EMBED):end]))
    except (ValueError, TypeError):
        return hand
    return embedded if embedded.same_as(hand, 1e-9) else hand


def _check_tree(source: str, links: list[str], joints: list[tuple[str, str, str]]) -> None:
    """A URDF's links and joints (name, parent, child) form a tree: names are unique, every joint
    joins two links of the file, no link is the child of two joints, and none lies on a cycle."""
    for kind, names in (("links", links), ("joints", [name for name, _, _ in joints])):
        seen: set[str] = set()
        for name in names:
            if name in seen:
                raise ValueError(f"{source}: two {kind} are called {name!r}")
            seen.add(name)
    known = set(links)
    up: dict[str, tuple[str, str]] = {}  # link -> (the joint above it, its parent link)
    for name, parent, child in joints:
        for role, link in (("parent", parent), ("child", child)):
            if link not in known:
                raise ValueError(f"{source}: joint {name!r} names {role} link {link!r}, which the file does not have")
        if child in up:
            raise ValueError(f"{source}: link {child!r} is the child of two joints ({up[child][0]!r} and {name!r})")
        up[child] = (name, parent)
    for link in links:  # each link's parents lead to a root, or round a cycle
        path, at = set(), link
        while at in up:
            if at in path:
                raise ValueError(f"{source}: the joints form a cycle through link {at!r}")
            path.add(at)
            at = up[at][1]


def _hand_from_chains(chains: list[_Chain], source: str, link_radius: float | None, palm_radius: float | None,
                      palm_thickness: float | None, kind: str, palm: str) -> Hand:
    """The hand of the fingers' chains of a ``kind`` file ("URDF" or "MJCF"), in the frame of its
    link or body ``palm`` (named in messages about that frame)."""
    chosen = (f" (the palm is {'link' if kind == 'URDF' else 'body'} {palm!r}; name another with "
              f"{PALM_KEYWORDS[kind]}= or --palm-link)")
    if not chains:
        raise ValueError(f"{source}: no finger found (no revolute joint below the palm)")
    n = len(chains[0].joints)
    for c in chains:
        if len(c.joints) != n:
            raise ValueError(f"{source}: every finger must have the same number of revolute joints; the finger of "
                             f"joint {c.joints[0]!r} has {len(c.joints)}, that of {chains[0].joints[0]!r} has {n} "
                             f"(hold extra joints with fixed_joints)")
    roots, dirs, lengths, rest, limits = [], [], [], [], []
    z = np.array([0.0, 0.0, 1.0])
    for c in chains:
        a0 = c.axes[0]
        if abs(float(_stable.dot(a0, z))) > PLANAR_TOLERANCE:
            raise ValueError(f"{source}: joint {c.joints[0]!r} has axis {np.round(a0, 6).tolist()} (palm frame), not "
                             f"normal to the palm normal z: its finger plane does not contain the palm normal{chosen}")
        signs = []
        for name, a in zip(c.joints, c.axes):
            if float(_stable.norm(np.cross(a, a0))) > PLANAR_TOLERANCE:
                raise ValueError(f"{source}: joint {name!r} breaks planarity: its axis {np.round(a, 6).tolist()} is "
                                 f"not parallel to {c.joints[0]!r}'s {np.round(a0, 6).tolist()} (palm frame); hold it "
                                 f"with fixed_joints={{{name!r}: value}}")
            signs.append(1.0 if float(_stable.dot(a, a0)) > 0 else -1.0)
        points = c.anchors + [cast(np.ndarray, c.tip)]
        names = c.joints + ["the fingertip"]
        for name, p in zip(names, points):
            off = abs(float(_stable.dot(p - c.anchors[0], a0)))
            if off > PLANAR_TOLERANCE:
                raise ValueError(f"{source}: joint {name!r} breaks planarity: it lies {off:.3g} m off the plane of "
                                 f"{c.joints[0]!r} (normal to its axis)")
        root = c.anchors[0]
        if abs(float(root[2])) > PLANAR_TOLERANCE:
            raise ValueError(f"{source}: joint {c.joints[0]!r} (a finger root) is at z = {root[2]:.6g} m in the palm "
                             f"frame, not on the palm's front face (z = 0){chosen}")
        u = np.cross(z, a0)
        u[2] = 0.0
        u /= _stable.norm(u)
        xi = [float(_stable.dot(p - root, u)) for p in points]
        eta = [float(p[2] - root[2]) for p in points]
        seg = np.diff(np.stack([xi, eta], axis=1), axis=0)
        ll = _stable.norm(seg)
        if np.any(ll <= 0):
            k = int(np.argmin(ll))
            raise ValueError(f"{source}: joint {names[k]!r} and {names[k + 1]!r} coincide: a link of zero length")
        absolute = _stable.arctan2(-seg[:, 0], seg[:, 1])
        rel = np.diff(absolute, prepend=0.0)
        rel = np.remainder(rel + math.pi, 2 * math.pi) - math.pi
        lim = []
        for q, s, (lo, hi) in zip(rel, signs, c.limits):
            a, b = q + s * lo, q + s * hi
            lim.append([min(a, b), max(a, b)])
        roots.append([root[0], root[1], 0.0])
        dirs.append(u)
        lengths.append(ll)
        rest.append(rel)
        limits.append(lim)
    radii = [r for c in chains for r in c.radii]
    if link_radius is None:
        if not radii:  # meshes, boxes or nothing: no radius to read
            warnings.warn(f"{source}: no collision cylinder or capsule on the finger links gives their radius; "
                          f"link_radius = 0 (the links are lines): pass link_radius (hugger plan --link-radius)",
                          stacklevel=4)
        link_radius = max(radii) if radii else 0.0
    kwargs = {}
    if palm_thickness is not None:
        kwargs["palm_thickness"] = palm_thickness
    try:  # the hand's own checks (a NaN length, say), named by the file as the checks above
        return Hand.from_layout(np.array(roots), np.array(dirs), np.array(lengths), rest=np.array(rest),
                                limits=np.array(limits), link_radius=link_radius, palm_radius=palm_radius,
                                name=os.path.splitext(os.path.basename(source))[0], **kwargs)
    except ValueError as exc:
        raise ValueError(f"{source}: {exc}") from None


# ------------------------------------------------------------------------------------- URDF

#: How far (rad) exported angles may lie beyond a joint limit, or beyond +-pi: rounding, not motion.
LIMIT_TOLERANCE = 1e-6


def _fixed_joints(value: Any) -> dict[str, float]:
    """``fixed_joints`` as {joint name: finite angle (rad)}, or a ValueError saying what is wrong."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ValueError(f"fixed_joints must map joint names to angles (rad), got {type(value).__name__}")
    out: dict[str, float] = {}
    for name, angle in value.items():
        try:  # (text and bools are not angles)
            x = number(f"fixed_joints[{name!r}]", angle)
        except ValueError:
            raise ValueError(f"fixed_joints[{name!r}] must be an angle (rad), got {shown(angle)}") from None
        if not math.isfinite(x):
            raise ValueError(f"fixed_joints[{name!r}] must be a finite angle (rad), got {shown(angle)}")
        out[str(name)] = x
    return out


def _within_limits(source: str, name: str, value: float, lower: Any, upper: Any, unit: str = "rad") -> None:
    """A joint held by fixed_joints must be held within its limits (rounding allowed)."""
    lo = 0.0 if lower is None else float(lower)  # (URDF's default for a side left out)
    hi = 0.0 if upper is None else float(upper)
    if not lo - LIMIT_TOLERANCE <= value <= hi + LIMIT_TOLERANCE:
        raise ValueError(f"{source}: joint {name!r} held at {value:g} {unit} is outside its limits "
                         f"[{lo:g}, {hi:g}] {unit}")


#: A joint's origin farther than this (m) from its parent link's frame is no hand's.
_FARTHEST_ORIGIN = 1e6


def _urdf_origin(source: str, j: Any) -> np.ndarray:
    """Joint ``j``'s origin (4, 4); a ValueError naming it when that is not a finite pose within
    :data:`_FARTHEST_ORIGIN`."""
    if j.origin is None:
        return np.eye(4)
    origin = np.asarray(j.origin, dtype=np.float64)
    xyz = origin[:3, 3]
    if not np.all(np.isfinite(xyz)) or float(np.abs(xyz).max()) > _FARTHEST_ORIGIN:
        raise ValueError(f"{source}: joint {j.name!r} has origin xyz {xyz.tolist()}: not a finite position within "
                         f"{_FARTHEST_ORIGIN:g} m")
    if not np.all(np.isfinite(origin)):
        raise ValueError(f"{source}: joint {j.name!r} has an origin rpy that is not finite")
    return origin


def _urdf_axis(source: str, j: Any) -> np.ndarray:
    """Joint ``j``'s axis in its frame as the file gives it (URDF's default x; not normalised); a
    ValueError naming it when that is no direction."""
    axis = np.asarray(j.axis if j.axis is not None else [1.0, 0.0, 0.0], dtype=np.float64)
    if not (np.all(np.isfinite(axis)) and float(_stable.norm(axis)) > 0.0):
        raise ValueError(f"{source}: joint {j.name!r} has axis {axis.tolist()}: not a direction")
    return axis


def _urdf_limits(source: str, j: Any) -> tuple[float, float]:
    """Revolute joint ``j``'s limits (rad), a side the file leaves out 0 as URDF says; a
    ValueError naming it when it has no ``<limit>`` (URDF requires one), or one with neither side
    (it could not move), or limits that are not numbers."""
    lim = j.limit
    if lim is None or (lim.lower is None and lim.upper is None):
        what = "has no <limit>, which URDF requires" if lim is None else \
            "has a <limit> with neither lower nor upper: by URDF's defaults (0) it cannot move"
        raise ValueError(f"{source}: revolute joint {j.name!r} {what}; give its limits (rad), make it 'continuous' "
                         f"(no limits), or hold it with fixed_joints")
    lo, hi = (0.0 if x is None else float(x) for x in (lim.lower, lim.upper))
    if math.isnan(lo) or math.isnan(hi):
        raise ValueError(f"{source}: joint {j.name!r} has limits [{lim.lower}, {lim.upper}]: not numbers")
    if not lo <= hi:
        raise ValueError(f"{source}: joint {j.name!r} has limits lower = {lim.lower} > upper = {lim.upper} rad")
    if max((abs(x) for x in (lo, hi) if math.isfinite(x)), default=0.0) > 2 * math.pi:
        warnings.warn(f"{source}: joint {j.name!r} has limits [{lim.lower}, {lim.upper}], beyond +-2 pi as if in "
                      f"degrees (URDF limits are radians): a bound beyond +-pi is no bound", stacklevel=4)
    return lo, hi


def from_urdf(path: str | os.PathLike[str], palm_link: str | None = None, fixed_joints: dict[str, float] | None = None,
              link_radius: float | None = None) -> Hand:
    """The hand of a URDF file (read with yourdfpy).

    ``palm_link`` (default the root link) is the palm: its frame is the palm frame P (z the palm
    normal, the front face at z = 0); a collision cylinder on it gives ``palm_radius`` and
    ``palm_thickness``. Links joined to it by fixed joints belong to the palm. Every revolute (or
    continuous) joint leaving the palm starts a finger, followed link by link to its end; the
    fingertip is the origin of a fixed child link of the last finger link, or else the far end of
    its collision cylinder. ``fixed_joints`` holds joints at the given values (rad): a spread
    joint, say, or a joint whose axis breaks planarity. ``link_radius`` defaults to the largest
    collision-cylinder radius of the finger links. ``ValueError`` names the joint that breaks
    planarity, or what else is missing.
    """
    yourdfpy = _need("yourdfpy")
    source = os.fspath(path)
    _check_root(source, "URDF")
    # yourdfpy reads a file that is not well-formed XML with a lenient parser, after logging the
    # strict parser's complaint: a file it reads so whole is taken (as it always was), one it then
    # reads wrong is refused with that complaint, not with the part found missing.
    with _Complaints("yourdfpy") as complaints:
        try:
            with kept():
                urdf = yourdfpy.URDF.load(source, build_scene_graph=False, load_meshes=False,
                                          load_collision_meshes=False)
        except Exception as exc:  # noqa: BLE001 - lxml and yourdfpy raise their own error types
            urdf, failure = None, f"{type(exc).__name__}: {exc}"
    xml_error = complaints.messages[0] if complaints.messages else None
    if urdf is None:
        raise ValueError(f"{source}: " + (f"not well-formed XML ({xml_error})" if xml_error else
                                          f"cannot read the URDF ({failure})")) from None
    try:
        return _urdf_hand(urdf.robot, source, palm_link, fixed_joints, link_radius)
    except ValueError:
        if xml_error is None:
            raise
        raise ValueError(f"{source}: not well-formed XML ({xml_error})") from None


def _urdf_hand(robot: Any, source: str, palm_link: str | None, fixed_joints: dict[str, float] | None,
               link_radius: float | None) -> Hand:
    """from_urdf's hand of the robot yourdfpy read from ``source``."""
    fixed = _fixed_joints(fixed_joints)
    names = {j.name for j in robot.joints}
    unknown = sorted(set(fixed) - names)
    if unknown:
        raise ValueError(f"{source}: fixed_joints names joints the file does not have: {unknown}")
    for j in robot.joints:
        if j.name in fixed and j.type in ("revolute", "prismatic") and j.limit is not None:
            _within_limits(source, j.name, fixed[j.name], j.limit.lower, j.limit.upper,
                           "m" if j.type == "prismatic" else "rad")
    links = {lk.name: lk for lk in robot.links}
    _check_tree(source, [lk.name for lk in robot.links], [(j.name, j.parent, j.child) for j in robot.joints])
    child_links = {j.child for j in robot.joints}
    roots = [lk.name for lk in robot.links if lk.name not in child_links]
    if palm_link is None and len(roots) != 1:
        raise ValueError(f"{source}: the URDF has {len(roots)} root links ({roots}); pass palm_link")
    palm = palm_link if palm_link is not None else roots[0]
    if palm not in links:
        raise ValueError(f"{source}: no link called {palm!r} (links: {sorted(links)})")
    children: dict[str, list[Any]] = {}
    for j in robot.joints:
        children.setdefault(j.parent, []).append(j)

    def motion(j: Any, value: float) -> np.ndarray:
        origin = _urdf_origin(source, j)
        if j.type in ("revolute", "continuous", "prismatic") and value != 0.0:
            axis = _urdf_axis(source, j)
            move = np.eye(4)
            if j.type == "prismatic":  # (held by fixed_joints, in m: it was taken at 0)
                move[:3, 3] = value * axis / _stable.norm(axis)
            else:
                move[:3, :3] = axis_angle(axis, value)
            return _stable.matmul(origin, move)
        return origin

    def is_fixed(j: Any) -> bool:
        return j.type == "fixed" or j.name in fixed

    def cylinders(link: str, frame: np.ndarray) -> list[tuple[np.ndarray, float, float]]:
        out = []
        for col in links[link].collisions:
            g = col.geometry
            if g is not None and g.cylinder is not None:
                o = np.eye(4) if col.origin is None else np.asarray(col.origin, dtype=np.float64)
                out.append((_stable.matmul(frame, o), float(g.cylinder.radius), float(g.cylinder.length)))
        return out

    # the palm group: links reached from the palm link through fixed joints
    frames = {palm: np.eye(4)}
    stack, starts = [palm], []
    while stack:  # breadth first: the fingers in the order of the file
        link = stack.pop(0)
        for j in children.get(link, []):
            if is_fixed(j):
                frames[j.child] = _stable.matmul(frames[link], motion(j, fixed.get(j.name, 0.0)))
                stack.append(j.child)
            elif j.type in ("revolute", "continuous"):
                starts.append((frames[link], j))
            else:
                raise ValueError(f"{source}: joint {j.name!r} is {j.type}: a finger has revolute joints only")
    chains = []
    for frame, j in starts:
        c = _Chain()
        while j is not None:
            f = _stable.matmul(frame, motion(j, 0.0))
            c.joints.append(j.name)
            c.anchors.append(f[:3, 3].copy())
            axis = _urdf_axis(source, j)
            c.axes.append(_stable.matmul(f[:3, :3], axis / _stable.norm(axis)))
            c.limits.append((-math.inf, math.inf) if j.type == "continuous" else _urdf_limits(source, j))
            if getattr(j, "mimic", None) is not None:
                warnings.warn(f"{source}: joint {j.name!r} mimics {j.mimic.joint!r} in the file; the hand moves "
                              f"each joint on its own (the coupling is not kept; hold the joints with fixed_joints "
                              f"where it matters)", stacklevel=3)
            c.radii += [r for _, r, _ in cylinders(j.child, f)]
            # follow the finger: through fixed joints to its next revolute joint
            nxt, tip, group, walk = None, None, [(j.child, f)], [(j.child, f)]
            while walk:
                link, lf = walk.pop()
                for k in children.get(link, []):
                    kf = _stable.matmul(lf, motion(k, fixed.get(k.name, 0.0)))
                    if is_fixed(k):
                        if tip is None:
                            tip = kf[:3, 3].copy()
                        walk.append((k.child, kf))
                        group.append((k.child, kf))
                    elif k.type in ("revolute", "continuous"):
                        if nxt is not None:
                            raise ValueError(f"{source}: the finger branches below joint {j.name!r} (joints "
                                             f"{nxt[1].name!r} and {k.name!r}): a finger is a single chain")
                        nxt = (lf, k)
                    else:
                        raise ValueError(f"{source}: joint {k.name!r} is {k.type}: a finger has revolute joints only")
            if nxt is None:
                if tip is None:
                    cyl = [x for link, lf in group for x in cylinders(link, lf)]
                    if not cyl:
                        raise ValueError(f"{source}: cannot find the fingertip after joint {j.name!r}: give its last "
                                         f"link a fixed child link at the tip, or a collision cylinder")
                    ends = [o[:3, 3] + s * o[:3, 2] * length / 2 for o, _, length in cyl for s in (1, -1)]
                    tip = max(ends, key=lambda e: float(_stable.norm(e - c.anchors[-1])))
                c.tip = tip
                j = None
            else:
                frame, j = nxt
        chains.append(c)
    palm_cyl = [x for link, lf in frames.items() for x in cylinders(link, lf)]
    palm_r = palm_t = None
    if palm_cyl:
        palm_r, palm_t = max(r for _, r, _ in palm_cyl), max(length for _, _, length in palm_cyl)
    return _exact(source, _hand_from_chains(chains, source, link_radius, palm_r, palm_t, "URDF", palm))


def _finger_geometry(hand: Hand) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per finger: anchors (N + 1, 3) of the rest pose in the palm frame and the joint axis a_m."""
    z = np.array([0.0, 0.0, 1.0])
    out = []
    for m in range(hand.fingers):
        u = hand.finger_directions[m]
        theta = np.cumsum(hand.rest_angles[m])
        d = -_stable.sin(theta)[:, None] * u + _stable.cos(theta)[:, None] * z
        pts = np.vstack([hand.finger_roots[m], hand.finger_roots[m] + np.cumsum(hand.link_lengths[m][:, None] * d, axis=0)])
        out.append((pts, np.cross(u, z)))
    return out


def _general(hand: Hand) -> Hand:
    """``hand`` in the general layout (the exporters' input), checked to be a Hand."""
    if not isinstance(hand, Hand):
        raise ValueError(f"hand must be a hugger.Hand, got {type(hand).__name__}")
    if hand.general:
        return hand
    phi = hand.finger_angles
    rim = rim_directions(phi)
    return Hand.from_layout(hand.palm_radius * rim, rim, hand.link_lengths, link_radius=hand.link_radius,
                            palm_radius=hand.palm_radius, palm_thickness=hand.palm_thickness, name=hand.name)


def to_urdf(hand: Hand, angles: Any = None, name: str = "hugger_hand") -> str:
    """The hand as URDF text (written with yourdfpy): a palm link ``palm`` (frame P, collision
    cylinder of the palm disk behind the front face), per finger links ``f{m}_l{n}`` on revolute
    joints ``f{m}_j{n}`` and a fixed tip link ``f{m}_tip``. Every joint frame is parallel to the
    palm frame; joint value 0 is the rest pose, so the URDF's joint value is q = theta - rest
    (rad) and its limits are the hand's less the rest angles (``continuous`` where unlimited).
    ``angles`` (M, N), hugger angles, adds a comment giving the joint values of that
    configuration (a grasp). :func:`from_urdf` reads the file back to the same hand."""
    yourdfpy = _need("yourdfpy", "writing a URDF")
    from yourdfpy import urdf as U

    g = _general(hand)
    def tf(xyz: Any, rot: Any = None) -> np.ndarray:
        t = np.eye(4)
        t[:3, 3] = xyz
        if rot is not None:
            t[:3, :3] = rot
        return t

    def along(d: np.ndarray) -> np.ndarray:  # a rotation taking z onto the unit vector d
        d = d / _stable.norm(d)
        v = np.cross([0.0, 0.0, 1.0], d)
        s, c = float(_stable.norm(v)), float(d[2])
        if s < 1e-15:
            return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
        return axis_angle(v, math.atan2(s, c))

    links = [U.Link(name="palm", collisions=[U.Collision(name="palm", origin=tf([0, 0, -g.palm_thickness / 2]),
                                                         geometry=U.Geometry(cylinder=U.Cylinder(
                                                             radius=g.palm_radius, length=g.palm_thickness)))])]
    joints = []
    limits, rest = g.joint_limits, g.rest_angles
    for m, (pts, axis) in enumerate(_finger_geometry(g)):
        parent = "palm"
        for n in range(g.links):
            child = f"f{m}_l{n}"
            d = pts[n + 1] - pts[n]
            links.append(U.Link(name=child, collisions=[U.Collision(
                name=child, origin=tf(d / 2, along(d)),
                geometry=U.Geometry(cylinder=U.Cylinder(radius=g.link_radius, length=float(g.link_lengths[m, n]))))]))
            span = _joint_range(limits[m, n], rest[m, n])
            xyz = pts[0] if n == 0 else pts[n] - pts[n - 1]
            joints.append(U.Joint(name=f"f{m}_j{n}", type="revolute" if span else "continuous", parent=parent,
                                  child=child, origin=tf(xyz), axis=axis,
                                  limit=U.Limit(effort=10.0, velocity=2.0, lower=span[0], upper=span[1])
                                  if span else None))
            parent = child
        links.append(U.Link(name=f"f{m}_tip"))
        joints.append(U.Joint(name=f"f{m}_tip", type="fixed", parent=parent, child=f"f{m}_tip",
                              origin=tf(pts[-1] - pts[-2])))
    robot = U.Robot(name=name, links=links, joints=joints)
    text = yourdfpy.URDF(robot=robot, build_scene_graph=False, load_meshes=False).write_xml_string()
    text = text.decode() if isinstance(text, bytes) else str(text)
    if angles is not None:
        values = " ".join(f"{k}={v!r}" for k, v in grasp_joint_values(hand, angles).items())
        text = _after_declaration(text, f"<!-- hugger grasp joint values (rad): {values} -->\n")
    return _embed(text, hand)


def _angle_limits(limits: np.ndarray) -> np.ndarray:
    """Joint limits ([..., 2] lower, upper; rad) within [-pi, pi], where joint angles lie (the
    relative angle of two directions): a side without a limit at +-pi."""
    return cast(np.ndarray, np.clip(limits, -math.pi, math.pi))


def _joint_range(limits: np.ndarray, rest: float) -> tuple[float, float] | None:
    """The range (rad) URDF and MJCF give a joint of ``limits`` (lower, upper) and ``rest`` angle:
    its _angle_limits less its rest angle; None for a joint without limits (URDF's continuous
    joint, MJCF's hinge without a range)."""
    if not np.isfinite(limits).any():
        return None
    lo, hi = _angle_limits(limits) - rest
    return float(lo), float(hi)


def _joint_values(hand: Hand, angles: Any) -> np.ndarray:
    """URDF/MJCF joint values q = theta - rest (M, N) of hugger angles (M, N)."""
    a = np.asarray(angles, dtype=np.float64)
    if a.shape != (hand.fingers, hand.links):
        raise ValueError(f"angles must have shape ({hand.fingers}, {hand.links}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("angles must be finite (rad)")
    # A plan's angles lie within these up to rounding; so do the files' ranges (_joint_range).
    lim = _angle_limits(hand.joint_limits)
    outside = np.argwhere((a < lim[..., 0] - LIMIT_TOLERANCE) | (a > lim[..., 1] + LIMIT_TOLERANCE))
    if len(outside):
        m, n = (int(i) for i in outside[0])
        lo, hi = hand.joint_limits[m, n]
        if lim[m, n, 0] == lo and lim[m, n, 1] == hi:
            where = f"that joint's limits [{lo:.6g}, {hi:.6g}]"
        elif not np.isfinite([lo, hi]).any():
            where = "[-pi, pi], where joint angles lie (that joint has no limits)"
        else:
            where = (f"[{lim[m, n, 0]:.6g}, {lim[m, n, 1]:.6g}] (that joint's limits [{lo:.6g}, {hi:.6g}] within "
                     f"[-pi, pi], where joint angles lie)")
        raise ValueError(f"angles[{m}, {n}] = {a[m, n]:.6g} rad is outside {where}")
    # Onto the limits where rounding put them beyond (the planner's slack): within the file's limits,
    # computed as these are, exactly (a controller may refuse a value 1e-16 beyond one).
    return cast(np.ndarray, np.clip(a, lim[..., 0], lim[..., 1]) - hand.rest_angles)


def grasp_joint_values(hand: Hand, angles: Any) -> dict[str, float]:
    """URDF/MJCF joint values ``{f{m}_j{n}: q}`` (rad) of hugger angles (M, N): q = theta - rest,
    with theta within the joint's limits and within [-pi, pi] (an angle beyond by rounding, up to
    LIMIT_TOLERANCE, is taken onto the bound; one farther is a ValueError)."""
    q = _joint_values(hand, angles)
    return {f"f{m}_j{n}": float(q[m, n]) for m in range(hand.fingers) for n in range(hand.links)}


# ------------------------------------------------------------------------------------- MJCF
def from_mjcf(path: str | os.PathLike[str], palm_body: str | None = None, fixed_joints: dict[str, float] | None = None,
              link_radius: float | None = None) -> Hand:
    """The hand of a MuJoCo MJCF file (compiled by MuJoCo itself), as :func:`from_urdf`:
    ``palm_body`` (default the first body below the world that has child bodies) is the palm,
    its frame the palm frame; each hinge below it starts a finger, one hinge per body; the
    fingertip is a site or child body of the last finger body, or else the far end of its capsule
    or cylinder geom, whose radius gives ``link_radius``. Joint ranges are read where
    ``limited``. Free, ball and slide joints are refused with their names."""
    mujoco = _need("mujoco")
    source = os.fspath(path)
    _check_root(source, "MJCF")
    try:
        model = mujoco.MjModel.from_xml_path(source)
    except (ValueError, OSError) as exc:  # MuJoCo's parse errors run over several lines: one here
        raise ValueError(f"{source}: cannot read the MJCF ({' '.join(str(exc).split())})") from None
    data = mujoco.MjData(model)
    fixed = _fixed_joints(fixed_joints)
    jname: Callable[[int], str] = lambda j: mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)  # noqa: E731
    bname: Callable[[int], str] = lambda b: mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b)  # noqa: E731
    names = {jname(j): j for j in range(model.njnt)}
    unknown = sorted(set(fixed) - set(names))
    if unknown:
        raise ValueError(f"{source}: fixed_joints names joints the file does not have: {unknown}")
    qpos = np.zeros(model.nq)
    for nm, v in fixed.items():
        if model.jnt_limited[names[nm]]:
            lo, hi = model.jnt_range[names[nm]]
            unit = "m" if model.jnt_type[names[nm]] == mujoco.mjtJoint.mjJNT_SLIDE else "rad"
            _within_limits(source, nm, v, lo, hi, unit)
        qpos[model.jnt_qposadr[names[nm]]] = v
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    kids: dict[int, list[int]] = {}
    b: int | None
    for b in range(1, model.nbody):
        kids.setdefault(int(model.body_parentid[b]), []).append(b)
    if palm_body is None:
        palm = next((b for b in kids.get(0, []) if b in kids), None)
        if palm is None:
            raise ValueError(f"{source}: no palm found (a body below the world with child bodies)")
    else:
        palm = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, palm_body)
        if palm < 0:
            raise ValueError(f"{source}: no body called {palm_body!r}")
    rot_p, pos_p = data.xmat[palm].reshape(3, 3), data.xpos[palm]
    to_palm: Callable[[Any], np.ndarray] = lambda x: _stable.matmul(rot_p.T, np.asarray(x) - pos_p)  # noqa: E731
    body_joints = {b: [j for j in range(model.njnt) if model.jnt_bodyid[j] == b] for b in range(model.nbody)}

    def moving(b: int) -> list[int]:
        out = []
        for j in body_joints[b]:
            t = model.jnt_type[j]
            if jname(j) in fixed:
                continue
            if int(t) != int(mujoco.mjtJoint.mjJNT_HINGE):
                raise ValueError(f"{source}: joint {jname(j)!r} of body {bname(b)!r} is not a hinge: a finger has "
                                 f"revolute joints only")
            out.append(j)
        if len(out) > 1:
            raise ValueError(f"{source}: body {bname(b)!r} has several hinges ({[jname(j) for j in out]}): hold all "
                             f"but one with fixed_joints")
        return out

    def geoms(b: int) -> list[tuple[float, np.ndarray, np.ndarray]]:
        out = []
        for g in range(model.ngeom):
            if model.geom_bodyid[g] == b and int(model.geom_type[g]) in (int(mujoco.mjtGeom.mjGEOM_CAPSULE),
                                                                    int(mujoco.mjtGeom.mjGEOM_CYLINDER)):
                mat = data.geom_xmat[g].reshape(3, 3)
                half = float(model.geom_size[g][1])
                c = data.geom_xpos[g]
                out.append((float(model.geom_size[g][0]), to_palm(c + half * mat[:, 2]), to_palm(c - half * mat[:, 2])))
        return out

    palm_group, stack, starts = {palm}, [palm], []
    while stack:
        b = stack.pop(0)
        for k in kids.get(b, []):
            if moving(k):
                starts.append(k)
            else:
                palm_group.add(k)
                stack.append(k)
    chains: list[_Chain] = []
    for b in starts:
        c = _Chain()
        while b is not None:
            j = moving(b)[0]
            c.joints.append(jname(j))
            c.anchors.append(to_palm(data.xanchor[j]))
            c.axes.append(_stable.matmul(rot_p.T, data.xaxis[j]))
            lo, hi = (float(x) for x in model.jnt_range[j])
            if math.isnan(lo) or math.isnan(hi):
                raise ValueError(f"{source}: joint {jname(j)!r} has range [{lo:g}, {hi:g}]: not numbers")
            if lo > hi:  # MuJoCo takes it for no limit (autolimits), as limited="false" asks
                warnings.warn(f"{source}: joint {jname(j)!r} has range [{lo:g}, {hi:g}] rad, lower above upper: "
                              f"MuJoCo takes it for no limit, and so does the hand", stacklevel=3)
            c.limits.append((lo, hi) if model.jnt_limited[j] else (-math.inf, math.inf))
            c.radii += [r for r, _, _ in geoms(b)]
            nxt = [k for k in kids.get(b, []) if moving(k)]
            if len(nxt) > 1:
                raise ValueError(f"{source}: the finger branches below body {bname(b)!r}: a finger is a single chain")
            if nxt:
                b = nxt[0]
                continue
            sites = [s for s in range(model.nsite) if model.site_bodyid[s] == b]
            still = [k for k in kids.get(b, [])]
            if sites:
                c.tip = to_palm(data.site_xpos[sites[0]])
            elif still:
                c.tip = to_palm(data.xpos[still[0]])
            else:
                ends = [e for _, e1, e2 in geoms(b) for e in (e1, e2)]
                if not ends:
                    raise ValueError(f"{source}: cannot find the fingertip of body {bname(b)!r}: add a site at the tip "
                                     f"or a capsule geom")
                c.tip = max(ends, key=lambda e: float(_stable.norm(e - c.anchors[-1])))
            b = None
        chains.append(c)
    palm_r = palm_t = None
    for g in range(model.ngeom):
        if model.geom_bodyid[g] in palm_group and int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_CYLINDER):
            palm_r, palm_t = float(model.geom_size[g][0]), 2.0 * float(model.geom_size[g][1])
    return _exact(source, _hand_from_chains(chains, source, link_radius, palm_r, palm_t, "MJCF",
                                            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, palm) or str(palm)))


def to_mjcf(hand: Hand, angles: Any = None, name: str = "hugger_hand") -> str:
    """The hand alone as MJCF text: a palm body (frame P, a cylinder geom behind the front face),
    per finger bodies ``f{m}_l{n}`` with hinges ``f{m}_j{n}`` (qpos 0 = rest, ranges the limits
    less the rest angles, unlimited joints without a range), capsule geoms and a tip site.
    ``angles`` (M, N) adds a keyframe ``grasp`` with those hugger angles. :func:`from_mjcf`
    reads it back to the same hand. (``hugger export-mjcf`` writes hand and object for
    simulation.)"""
    import xml.etree.ElementTree as ET

    g = _general(hand)
    f: Callable[[Any], str] = lambda v: " ".join(repr(float(x)) for x in np.ravel(v))  # noqa: E731
    root = ET.Element("mujoco", model=name)
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    world = ET.SubElement(root, "worldbody")
    palm = ET.SubElement(world, "body", name="palm")
    ET.SubElement(palm, "geom", name="palm", type="cylinder", pos=f([0, 0, -g.palm_thickness / 2]),
                  size=f([g.palm_radius, g.palm_thickness / 2]))
    limits, rest = g.joint_limits, g.rest_angles
    for m, (pts, axis) in enumerate(_finger_geometry(g)):
        parent, base = palm, np.zeros(3)
        for n in range(g.links):
            body = ET.SubElement(parent, "body", name=f"f{m}_l{n}", pos=f(pts[n] - base))
            attrs = {"name": f"f{m}_j{n}", "type": "hinge", "axis": f(axis)}
            span = _joint_range(limits[m, n], rest[m, n])
            if span:
                lo, hi = span
                attrs["range"] = f([lo, max(hi, lo + 1e-12)])  # MuJoCo needs lower < upper: a held joint
                attrs["limited"] = "true"
            ET.SubElement(body, "joint", attrs)
            if g.link_radius > 0:  # zero-thickness links: no geom (the tip site ends the finger)
                ET.SubElement(body, "geom", name=f"f{m}_l{n}", type="capsule",
                              fromto=f(np.r_[0, 0, 0, pts[n + 1] - pts[n]]), size=f([g.link_radius]))
            parent, base = body, pts[n]
        ET.SubElement(parent, "site", name=f"f{m}_tip", pos=f(pts[-1] - pts[-2]))
    if angles is not None:
        key = ET.SubElement(root, "keyframe")
        ET.SubElement(key, "key", name="grasp", qpos=f(_joint_values(g, angles)))
    ET.indent(root)
    return _embed(ET.tostring(root, encoding="unicode") + "\n", hand)
