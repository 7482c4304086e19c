"""The hand model (docs/model.md): a round palm and M planar fingers of N links."""
from __future__ import annotations

import difflib
import json
import warnings
from typing import Any, Callable

import numpy as np

from . import _core, _stable
from ._checks import positive, real_array, shown, whole

from ._types import MAX_FINGERS, MAX_LINKS  # noqa: F401  (hugger.hand.MAX_FINGERS as before)

#: Hard limits (m) on the hand's lengths (link lengths, palm radius and thickness). Below
#: ``MIN_LENGTH`` the engine's absolute tolerances (1e-7 m keeps two links apart) are no longer
#: small against a link; above ``MAX_LENGTH`` the numbers are not metres of any hand.
MIN_LENGTH = 1e-5
MAX_LENGTH = 1e6

#: A hand or object whose size (m) falls outside this range is accepted with a ``UserWarning``:
#: it was most likely given in millimetres (a 2 cm link becomes 20 "m") or centimetres. Objects
#: are measured by the longest side of their bounding box, hands by the larger of the palm's
#: diameter and the longest finger.
PLAUSIBLE_SIZE = (1e-3, 3.0)

#: Tolerance of the rigid-pose check: |R^T R - I| and |det R - 1|. The engine owns it (the
#: planner refuses a start pose by the same rule); Python reads it from the compiled module.
RIGID_TOLERANCE: float = _core.RIGID_TOLERANCE


def rim_directions(finger_angles: Any) -> np.ndarray:
    """(M, 3): (cos phi_m, sin phi_m, 0) for the finger angles phi_m (rad), the same bits on every
    processor (hugger._stable); ``ValueError`` for an angle that is not finite."""
    phi = np.asarray(finger_angles, dtype=np.float64).reshape(-1)
    if not np.all(np.isfinite(phi)):
        raise ValueError(f"finger_angles must be finite, got {phi.tolist()}")
    return np.stack([_stable.cos(phi), _stable.sin(phi), np.zeros(phi.shape)], axis=1)


def _size(name: str, value: Any, allow_zero: bool = False) -> float:
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be a number, got {shown(value)}")
    v = positive(name, value, allow_zero)
    if v > MAX_LENGTH:
        raise ValueError(f"{name} = {v:g} m is larger than {MAX_LENGTH:g} m: sizes are in metres")
    return v


def implausible_size(what: str, size: float) -> str | None:
    """The warning text when ``size`` (m) is outside :data:`PLAUSIBLE_SIZE`, else None."""
    lo, hi = PLAUSIBLE_SIZE
    if size > hi:
        return (f"{what} is {size:g} m across, implausibly large for a grasp (more than {hi:g} m): hugger works "
                f"in metres; was it given in millimetres? (scale it by 0.001)")
    if size < lo:
        return (f"{what} is {size * 1000:g} mm across, implausibly small for a grasp (less than {lo * 1000:g} mm): "
                f"hugger works in metres")
    return None


def plausible_hand(force: bool, how: str, make: Callable[[], Hand]) -> Hand:
    """The hand ``make()`` returns (``Hand(...)``, a preset, a URDF file's), refused with a
    ``ValueError`` when its size is implausible for a grasp (:attr:`Hand.size_warning`:
    millimetres read as metres) unless ``force``, as a mesh of implausible size is; ``how``: how to
    force it, for the message. Forced, it is warned of."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hand = make()
    if hand.size_warning and not force:
        raise ValueError(f"{hand.size_warning}; refused (give its sizes in metres, or {how})")
    for w in caught:  # (the size warning among them, when forced)
        warnings.warn(w.message, stacklevel=3)
    return hand


class Hand:
    """Immutable hand description; sizes in metres.

    Parameters
    ----------
    fingers, links
        M fingers, each of N links.
    link_length
        A scalar (all links equal) or an (M, N) array of per-link lengths.
    link_radius
        Radius of the capsule links (0: zero-thickness links, as in the paper).
    palm_radius, palm_thickness
        The palm disk; finger roots sit on the rim of its front face.

    :meth:`from_layout` describes real hands instead: per finger a root on the palm's front
    face and an in-plane outward direction, per joint limits, per finger rest angles; presets
    and URDF/MJCF import are in :mod:`hugger.hands`.
    """

    name: str | None = None
    #: to_json's text, with the name it was made for.
    _json: tuple[str | None, str] | None = None

    def __init__(self, fingers: int = 5, links: int = 5, link_length: Any = 0.02, link_radius: float = 0.004,
                 palm_radius: float = 0.03, palm_thickness: float = 0.01) -> None:
        m, n = whole("fingers", fingers), whole("links", links)
        if not 1 <= m <= MAX_FINGERS:
            raise ValueError(f"fingers must be between 1 and {MAX_FINGERS}, got {m}")
        if not 1 <= n <= MAX_LINKS:
            raise ValueError(f"links must be between 1 and {MAX_LINKS}, got {n}")
        lengths = real_array("link_length", link_length)
        if lengths.ndim == 0:
            lengths = np.full((m, n), float(lengths))
        if lengths.shape != (m, n):
            raise ValueError(f"link_length must be a scalar or a (fingers, links) = ({m}, {n}) array, got shape {lengths.shape}")
        self._build(lengths, _size("link_radius", link_radius, allow_zero=True), palm_radius, palm_thickness)

    @classmethod
    def from_layout(cls, roots: Any, directions: Any, link_lengths: Any, rest: Any = None, limits: Any = None,
                    link_radius: float = 0.004, palm_radius: float | None = None, palm_thickness: float = 0.01,
                    name: str | None = None) -> Hand:
        """A hand of general layout (a real hand); every array in the palm frame P (metres, radians).

        Parameters
        ----------
        roots
            (M, 3) finger roots R_m on the palm's front face: z = 0, within ``palm_radius`` of P_o.
        directions
            (M, 3) in-plane outward directions u_m, z = 0 (normalised here). Finger m moves in the
            plane through R_m spanned by u_m and the palm normal; flexion turns it toward -u_m.
        link_lengths
            (M, N) link lengths, or a scalar.
        rest
            (M, N) rest angles: the FROZEN (open) finger; default all 0, straight along the palm
            normal. ``rest[m, 0] = -pi/2`` lays link 0 along the palm, along +u_m.
        limits
            (M, N, 2) [lower, upper] joint limits (rad, relative angles as in
            :meth:`forward`); default unlimited. A bound at or beyond +-pi is no bound (angles
            lie in [-pi, pi]); ``lower == upper`` holds a joint fixed.
        link_radius, palm_thickness
            As for :class:`Hand`.
        palm_radius
            The palm disk; default the smallest centred disk holding every root and a link's
            radius around it (at least 1 mm).

        ``ValueError`` says why a layout is refused: a root off the palm, a direction out of
        the palm plane, limits with lower > upper, rest angles outside their limits or behind
        the palm's front plane, fingers that intersect at rest.
        """
        r = real_array("roots", roots)
        if r.ndim != 2 or r.shape[1] != 3:
            raise ValueError(f"roots must be an (M, 3) array, got shape {r.shape}")
        m = r.shape[0]
        if not 1 <= m <= MAX_FINGERS:
            raise ValueError(f"the hand must have between 1 and {MAX_FINGERS} fingers, got {m} roots")
        d = real_array("directions", directions)
        if d.shape != (m, 3):
            raise ValueError(f"directions must be an (M, 3) = ({m}, 3) array like roots, got shape {d.shape}")
        lengths = real_array("link_lengths", link_lengths)
        if lengths.ndim == 0:
            raise ValueError("link_lengths must be an (M, N) array (a scalar does not say N)")
        if lengths.ndim != 2 or lengths.shape[0] != m:
            raise ValueError(f"link_lengths must be an (M, N) array with M = {m} rows, got shape {lengths.shape}")
        n = lengths.shape[1]
        if not 1 <= n <= MAX_LINKS:
            raise ValueError(f"links must be between 1 and {MAX_LINKS}, got {n}")
        for label, a in (("roots", r), ("directions", d)):
            if not np.all(np.isfinite(a)):
                raise ValueError(f"{label} hold non-finite numbers")
        q = np.zeros((m, n)) if rest is None else real_array("rest", rest)
        if q.shape != (m, n):
            raise ValueError(f"rest must be an (M, N) = ({m}, {n}) array, got shape {q.shape}")
        if limits is None:
            lo, hi = np.full((m, n), -np.inf), np.full((m, n), np.inf)
        else:
            lim = real_array("limits", limits)
            if lim.shape != (m, n, 2):
                raise ValueError(f"limits must be an (M, N, 2) = ({m}, {n}, 2) array of [lower, upper], got shape {lim.shape}")
            lo, hi = lim[..., 0].copy(), lim[..., 1].copy()
            lo[lo <= -np.pi + 1e-12] = -np.inf  # at or beyond -pi: no bound (rounding allowed)
            hi[hi >= np.pi - 1e-12] = np.inf
        radius = _size("link_radius", link_radius, allow_zero=True)
        if palm_radius is None:
            palm_radius = max(1e-3, float(np.hypot(r[:, 0], r[:, 1]).max()) + radius)
        hand = cls.__new__(cls)
        hand._build(lengths, radius, palm_radius, palm_thickness, roots=r, directions=d, rest=q, lower=lo, upper=hi)
        hand.name = None if name is None else str(name)
        return hand

    def _build(self, lengths: np.ndarray, radius: float, palm_radius: Any, palm_thickness: Any,
               **layout: np.ndarray) -> None:
        """The one path of ``__init__`` and :meth:`from_layout` once counts and arrays are checked:
        checks the palm and the link lengths, builds the engine's hand (a general layout when
        ``layout`` is given) and warns, at their caller, of an implausible size."""
        palm_r, palm_t = _size("palm_radius", palm_radius), _size("palm_thickness", palm_thickness)
        if not np.all(np.isfinite(lengths)) or not np.all(lengths > 0):
            bad = float(lengths[~(np.isfinite(lengths) & (lengths > 0))][0])
            raise ValueError(f"link_length must be a positive finite number, got {bad!r}")
        for name, value in (("link_length", float(lengths.min())), ("palm_radius", palm_r), ("palm_thickness", palm_t)):
            if value < MIN_LENGTH:
                raise ValueError(f"{name} = {value:g} m is smaller than {MIN_LENGTH:g} m, below what the engine "
                                 f"resolves (its tolerances are absolute, about 1e-7 m)")
        if lengths.max() > MAX_LENGTH:
            raise ValueError(f"link_length = {lengths.max():g} m is larger than {MAX_LENGTH:g} m: sizes are in metres")
        m, n = lengths.shape
        self._core = _core.HandModel(m, n, lengths, radius, palm_r, palm_t, **layout)
        message = self.size_warning
        if message:
            warnings.warn(message, UserWarning, stacklevel=3)

    @property
    def size_warning(self) -> str | None:
        """The warning the hand drew when made, for a size implausible for a grasp (the largest of
        its palm's diameter and thickness, its longest finger and its links' diameter outside
        :data:`PLAUSIBLE_SIZE`: millimetres read as metres), or None."""
        return implausible_size("the hand", max(2.0 * self.palm_radius, self.palm_thickness, self.reach,
                                                2.0 * self.link_radius))

    @property
    def fingers(self) -> int:
        """M, the number of fingers."""
        return self._core.fingers

    @property
    def links(self) -> int:
        """N, the number of links per finger."""
        return self._core.links

    @property
    def link_lengths(self) -> np.ndarray:
        """(M, N) link lengths (m)."""
        return self._core.link_lengths

    @property
    def link_radius(self) -> float:
        """Capsule radius of the links (m)."""
        return self._core.link_radius

    @property
    def palm_radius(self) -> float:
        """Palm disk radius (m)."""
        return self._core.palm_radius

    @property
    def palm_thickness(self) -> float:
        """Palm disk thickness (m)."""
        return self._core.palm_thickness

    @property
    def finger_angles(self) -> np.ndarray:
        """phi_m (rad): the angle of each finger's direction u_m about the palm normal."""
        return np.asarray(self._core.finger_angles)

    @property
    def general(self) -> bool:
        """True for a hand made by from_layout (roots, directions, rest angles, limits)."""
        return bool(self._core.general)

    @property
    def finger_roots(self) -> np.ndarray:
        """(M, 3) roots R_m in the palm frame (m)."""
        return self._core.finger_roots

    @property
    def finger_directions(self) -> np.ndarray:
        """(M, 3) in-plane outward directions u_m in the palm frame (unit)."""
        return self._core.finger_directions

    @property
    def rest_angles(self) -> np.ndarray:
        """(M, N) rest (FROZEN) joint angles (rad)."""
        return self._core.rest_angles

    @property
    def joint_limits(self) -> np.ndarray:
        """(M, N, 2) [lower, upper] joint limits (rad); -inf / inf where a joint is unlimited."""
        return np.stack([self._core.lower, self._core.upper], axis=-1)

    @property
    def has_limits(self) -> bool:
        """True when some joint has a finite limit."""
        return bool(self._core.has_limits)

    @property
    def reach(self) -> float:
        """Length of the longest finger (m)."""
        return float(self.link_lengths.sum(axis=1).max())

    def forward(self, palm_pose: Any, angles: Any) -> np.ndarray:
        """Joint positions (M, N+1, 3) in the world (m) from the rigid palm pose T_WP (4, 4) and joint
        angles (M, N) in radians (docs/model.md)."""
        a = real_array("angles", angles)
        if a.shape != (self.fingers, self.links):
            raise ValueError(f"angles must have shape ({self.fingers}, {self.links}), got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError("angles hold non-finite numbers")
        return self._core.forward(real_array("palm_pose", palm_pose), a)  # the engine checks the pose

    def angles_from_joints(self, palm_pose: Any, joints: Any) -> np.ndarray:
        """Joint angles (M, N) in radians from joint positions (M, N+1, 3) in the world (m)."""
        j = real_array("joints", joints)
        if j.shape != (self.fingers, self.links + 1, 3):
            raise ValueError(f"joints must have shape ({self.fingers}, {self.links + 1}, 3), got {j.shape}")
        if not np.all(np.isfinite(j)):
            raise ValueError("joints hold non-finite numbers")
        return self._core.angles_from_joints(real_array("palm_pose", palm_pose), j)

    def roots(self, palm_pose: Any) -> np.ndarray:
        """Finger roots R_m (M, 3) in the world (m) for the rigid palm pose T_WP (4, 4)."""
        return self._core.roots(real_array("palm_pose", palm_pose))

    def to_dict(self) -> dict[str, Any]:
        """The hand as in the trajectory file's ``hand_json``. A general layout adds
        ``finger_roots`` (M x 3), ``finger_directions`` (M x 3), ``rest_angles`` (M x N) and, when
        a joint is limited, ``joint_limits`` (M x N x 2, finite: an unlimited bound is written as
        +-pi, which no angle passes), and ``name`` when the hand has one."""
        d = {
            "fingers": self.fingers,
            "links": self.links,
            "link_lengths": self.link_lengths.tolist(),
            "link_radius": self.link_radius,
            "palm_radius": self.palm_radius,
            "palm_thickness": self.palm_thickness,
            "finger_angles": self.finger_angles.tolist(),
        }
        if self.general:
            d["finger_roots"] = self.finger_roots.tolist()
            d["finger_directions"] = self.finger_directions.tolist()
            d["rest_angles"] = self.rest_angles.tolist()
            if self.has_limits:
                d["joint_limits"] = np.clip(self.joint_limits, -np.pi, np.pi).tolist()
        if self.name:
            d["name"] = self.name
        return d

    def to_json(self) -> str:
        """:meth:`to_dict` as JSON (every trajectory records it): made once per hand and name, as
        the hand is immutable (its ``name`` alone may be set after it is made)."""
        made = self._json
        if made is None or made[0] != self.name:
            made = self._json = (self.name, json.dumps(self.to_dict()))
        return made[1]

    @classmethod
    def from_dict(cls, d: dict[str, Any], strict: bool = False) -> Hand:
        """The hand of :meth:`to_dict` (or a trajectory file's ``hand_json``); ``ValueError`` if a key is
        missing or a value is not valid. Keys it does not know are ignored (a newer writer's), or,
        with ``strict`` (a hand file a person wrote), refused, naming the nearest known key."""
        if not isinstance(d, dict):
            raise ValueError(f"a hand description must be a dict, got {type(d).__name__}")
        keys = ("fingers", "links", "link_lengths", "link_radius", "palm_radius", "palm_thickness")
        missing = [k for k in keys if k not in d]
        if missing:
            raise ValueError(f"the hand description lacks {missing}")
        layout_keys = ("finger_roots", "finger_directions", "rest_angles", "joint_limits")
        known = (*keys, "finger_angles", *layout_keys, "name")
        for key in d if strict else ():
            if key not in known:  # a misspelt key would leave the hand another than described
                close = difflib.get_close_matches(str(key), known, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else f" (the keys: {', '.join(known)})"
                raise ValueError(f"the hand description has an unknown key {key!r}{hint}")
        integral: Callable[[Any], Any] = lambda x: int(x) if isinstance(x, float) and x.is_integer() else x  # noqa: E731  (JSON may say 5.0)
        fingers, links = integral(d["fingers"]), integral(d["links"])
        # The rim angles as given (default 2 pi m / M): fingers at other angles are a layout too.
        phi: np.ndarray | None = None
        spread = False
        if "finger_angles" in d:
            m = whole("fingers", fingers)
            phi = real_array("finger_angles", d["finger_angles"])
            if phi.shape != (m,):
                raise ValueError(f"finger_angles must hold {m} angles, got shape {phi.shape}")
            spread = not np.allclose(phi, 2 * np.pi * np.arange(m) / m, rtol=0.0, atol=1e-12)
        if not spread and not any(k in d for k in layout_keys):
            hand = cls(fingers=fingers, links=links, link_length=d["link_lengths"], link_radius=d["link_radius"],
                       palm_radius=d["palm_radius"], palm_thickness=d["palm_thickness"])
            hand.name = d.get("name") if isinstance(d.get("name"), str) else None
            return hand
        m, n = whole("fingers", fingers), whole("links", links)
        if not (1 <= m <= MAX_FINGERS and 1 <= n <= MAX_LINKS):
            raise ValueError(f"fingers and links must be in 1..{MAX_FINGERS} and 1..{MAX_LINKS}, got {m}, {n}")
        palm_r = _size("palm_radius", d["palm_radius"])
        rim = rim_directions(2 * np.pi * np.arange(m) / m if phi is None else phi)
        lengths = real_array("link_lengths", d["link_lengths"])
        if lengths.ndim == 0:
            lengths = np.full((m, n), float(lengths))
        elif lengths.size == m * n:
            lengths = lengths.reshape(m, n)
        return cls.from_layout(roots=d.get("finger_roots", palm_r * rim), directions=d.get("finger_directions", rim),
                               link_lengths=lengths, rest=d.get("rest_angles"), limits=d.get("joint_limits"),
                               link_radius=d["link_radius"], palm_radius=palm_r, palm_thickness=d["palm_thickness"],
                               name=d.get("name") if isinstance(d.get("name"), str) else None)

    def same_as(self, other: Hand, tol: float = 1e-9) -> bool:
        """True when ``other`` describes the same hand: equal counts and, within ``tol`` (m or rad),
        equal sizes, roots, directions, rest angles and limits (infinite limits equal)."""
        tol = positive("tol", tol, allow_zero=True)
        if not isinstance(other, Hand) or (self.fingers, self.links) != (other.fingers, other.links):
            return False
        pairs = [(self.link_lengths, other.link_lengths), (self.finger_roots, other.finger_roots),
                 (self.finger_directions, other.finger_directions), (self.rest_angles, other.rest_angles),
                 (np.array([self.link_radius, self.palm_radius, self.palm_thickness]),
                  np.array([other.link_radius, other.palm_radius, other.palm_thickness]))]
        if not all(np.allclose(a, b, rtol=0.0, atol=tol) for a, b in pairs):
            return False
        la, lb = self.joint_limits, other.joint_limits
        same_inf = np.array_equal(np.isinf(la), np.isinf(lb)) and np.array_equal(la[np.isinf(la)], lb[np.isinf(lb)])
        return same_inf and bool(np.allclose(la[np.isfinite(la)], lb[np.isfinite(lb)], rtol=0.0, atol=tol))

    @classmethod
    def from_urdf(cls, path: Any, palm_link: str | None = None, fixed_joints: dict[str, float] | None = None,
                  link_radius: float | None = None) -> Hand:
        """The hand of a URDF file: see :func:`hugger.hands.from_urdf` (needs ``hugger[hands]``)."""
        from .hands import from_urdf
        return from_urdf(path, palm_link=palm_link, fixed_joints=fixed_joints, link_radius=link_radius)

    @classmethod
    def from_mjcf(cls, path: Any, palm_body: str | None = None, fixed_joints: dict[str, float] | None = None,
                  link_radius: float | None = None) -> Hand:
        """The hand of a MuJoCo MJCF file: see :func:`hugger.hands.from_mjcf` (needs MuJoCo)."""
        from .hands import from_mjcf
        return from_mjcf(path, palm_body=palm_body, fixed_joints=fixed_joints, link_radius=link_radius)

    def to_urdf(self, path: Any = None, angles: Any = None) -> str:
        """The hand as URDF text (see :func:`hugger.hands.to_urdf`), also written to ``path``."""
        from ._files import write_atomic
        from .hands.robot import to_urdf
        text = to_urdf(self, angles)
        if path is not None:
            write_atomic(path, text)
        return text

    def __repr__(self) -> str:
        ll = self.link_lengths
        length = f"{ll[0, 0]:g}" if np.all(ll == ll[0, 0]) else "per-link"
        layout = ", general layout" if self.general else ""
        name = f"{self.name!r}, " if self.name else ""
        return (f"Hand({name}fingers={self.fingers}, links={self.links}, link_length={length}, "
                f"link_radius={self.link_radius:g}, palm_radius={self.palm_radius:g}, "
                f"palm_thickness={self.palm_thickness:g}{layout})")
