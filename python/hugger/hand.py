"""The hand model (DESIGN.md section 2): a round palm and M planar fingers of N links."""
from __future__ import annotations

import json
import numbers
from typing import Any

import numpy as np

from . import _core


def _count(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    return int(value)


def _size(name: str, value: Any, allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise ValueError(f"{name} must be a {'non-negative' if allow_zero else 'positive'} finite number, got {value!r}")
    return v


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
    """

    def __init__(self, fingers: int = 5, links: int = 5, link_length: Any = 0.02, link_radius: float = 0.004,
                 palm_radius: float = 0.03, palm_thickness: float = 0.01) -> None:
        m, n = _count("fingers", fingers), _count("links", links)
        if not 1 <= m <= 64:
            raise ValueError(f"fingers must be between 1 and 64, got {m}")
        if not 1 <= n <= 256:
            raise ValueError(f"links must be between 1 and 256, got {n}")
        lengths = np.asarray(link_length, dtype=np.float64)
        if lengths.ndim == 0:
            lengths = np.full((m, n), float(lengths))
        if lengths.shape != (m, n):
            raise ValueError(f"link_length must be a scalar or a (fingers, links) = ({m}, {n}) array, got shape {lengths.shape}")
        self._core = _core.HandModel(m, n, lengths, _size("link_radius", link_radius, allow_zero=True),
                                     _size("palm_radius", palm_radius), _size("palm_thickness", palm_thickness))

    fingers = property(lambda self: self._core.fingers, doc="M, the number of fingers")
    links = property(lambda self: self._core.links, doc="N, the number of links per finger")
    link_lengths = property(lambda self: self._core.link_lengths, doc="(M, N) link lengths (m)")
    link_radius = property(lambda self: self._core.link_radius, doc="capsule radius of the links (m)")
    palm_radius = property(lambda self: self._core.palm_radius, doc="palm disk radius (m)")
    palm_thickness = property(lambda self: self._core.palm_thickness, doc="palm disk thickness (m)")
    finger_angles = property(lambda self: np.asarray(self._core.finger_angles), doc="phi_m (rad) of each root")

    @property
    def reach(self) -> float:
        """Length of the longest finger (m)."""
        return float(self.link_lengths.sum(axis=1).max())

    def forward(self, palm_pose: Any, angles: Any) -> np.ndarray:
        """Joint positions (M, N+1, 3) in the world from palm pose (4, 4) and angles (M, N)."""
        return self._core.forward(np.asarray(palm_pose, dtype=np.float64), np.asarray(angles, dtype=np.float64))

    def angles_from_joints(self, palm_pose: Any, joints: Any) -> np.ndarray:
        """Joint angles (M, N) from joint positions (M, N+1, 3)."""
        return self._core.angles_from_joints(np.asarray(palm_pose, dtype=np.float64), np.asarray(joints, dtype=np.float64))

    def roots(self, palm_pose: Any) -> np.ndarray:
        """Finger roots R_m (M, 3) in the world."""
        return self._core.roots(np.asarray(palm_pose, dtype=np.float64))

    def to_dict(self) -> dict:
        """The hand as in the trajectory file's ``hand_json`` (DESIGN.md section 5)."""
        return {
            "fingers": self.fingers,
            "links": self.links,
            "link_lengths": self.link_lengths.tolist(),
            "link_radius": self.link_radius,
            "palm_radius": self.palm_radius,
            "palm_thickness": self.palm_thickness,
            "finger_angles": self.finger_angles.tolist(),
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @classmethod
    def from_dict(cls, d: dict) -> Hand:
        return cls(fingers=int(d["fingers"]), links=int(d["links"]), link_length=np.asarray(d["link_lengths"], dtype=float),
                   link_radius=float(d["link_radius"]), palm_radius=float(d["palm_radius"]),
                   palm_thickness=float(d["palm_thickness"]))

    def __repr__(self) -> str:
        ll = self.link_lengths
        length = f"{ll[0, 0]:g}" if np.all(ll == ll[0, 0]) else "per-link"
        return (f"Hand(fingers={self.fingers}, links={self.links}, link_length={length}, link_radius={self.link_radius:g}, "
                f"palm_radius={self.palm_radius:g}, palm_thickness={self.palm_thickness:g})")
