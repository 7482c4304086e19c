"""Preset hands with dimensions from the manufacturers' public data (see docs/hands.md).

Each is a :class:`hugger.Hand` of general layout, palm frame as in :meth:`Hand.from_layout`:
z the palm normal, the front face at z = 0. They are "-like": a real hand's fingers are not
capsules and its joints may be coupled; only the planar-chain geometry and the joint ranges the
planner needs are kept.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..hand import Hand

_DEG = math.pi / 180.0


@dataclass(frozen=True)
class Preset:
    """A named hand: ``build()`` makes it; ``source`` says where its dimensions come from."""

    name: str
    description: str
    source: str
    build: Callable[[], Hand]


def barrett_bh8() -> Hand:
    """BarrettHand BH8-282-like, 3 fingers x 3 links, spread held at 0 (F1 and F2 side by side,
    opposing F3). Barrett's kinematics: spread axes Aw = 25 mm from the palm centre; per finger
    the knuckle offset A1 = 50 mm (along the palm: link 0, held fixed), the proximal link A2 =
    70 mm and the distal link A3 = 50 mm; proximal flexion 0-140 degrees (here 0-90: no link may
    pass behind the palm's front plane), distal 0-48 degrees relative to the proximal link."""
    aw = 0.025
    roots = [[-aw, 0.0, 0.0], [aw, 0.0, 0.0], [0.0, 0.0, 0.0]]
    dirs = [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]
    lengths = np.tile([0.050, 0.070, 0.050], (3, 1))
    rest = np.tile([-math.pi / 2, math.pi / 2, 0.0], (3, 1))
    limits = np.tile([[-math.pi / 2, -math.pi / 2], [math.pi / 2, math.pi], [0.0, 48 * _DEG]], (3, 1, 1))
    return Hand.from_layout(roots, dirs, lengths, rest=rest, limits=limits, link_radius=0.0095,
                            palm_radius=0.045, palm_thickness=0.02, name="barrett_bh8")


def robotiq_3f() -> Hand:
    """Robotiq 3-Finger Adaptive Gripper-like, 3 fingers x 3 phalanges, basic (parallel) mode:
    fingers B and C side by side opposing finger A. Phalanges 57, 38 and 22 mm; opening up to
    about 155 mm between A and B/C; phalanx ranges about 0-70, 0-90 and -55-+43 degrees."""
    roots = [[0.0, -0.0425, 0.0], [-0.0365, 0.0425, 0.0], [0.0365, 0.0425, 0.0]]
    dirs = [[0.0, -1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    lengths = np.tile([0.057, 0.038, 0.022], (3, 1))
    limits = np.tile([[-5 * _DEG, 70 * _DEG], [0.0, 90 * _DEG], [-55 * _DEG, 43 * _DEG]], (3, 1, 1))
    return Hand.from_layout(roots, dirs, lengths, limits=limits, link_radius=0.010, palm_radius=0.065,
                            palm_thickness=0.03, name="robotiq_3f")


def parallel_3link() -> Hand:
    """A parallel two-finger gripper with two opposed 3-link fingers (30, 25 and 20 mm) 70 mm
    apart, flexion -20 to +100 degrees per joint: a generic multi-link gripper."""
    roots = [[0.035, 0.0, 0.0], [-0.035, 0.0, 0.0]]
    dirs = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]
    lengths = np.tile([0.030, 0.025, 0.020], (2, 1))
    limits = np.tile([-20 * _DEG, 100 * _DEG], (2, 3, 1))
    return Hand.from_layout(roots, dirs, lengths, limits=limits, link_radius=0.006, palm_radius=0.04,
                            palm_thickness=0.015, name="parallel_3link")


def paper_5x5() -> Hand:
    """The paper's idealised hand as `hugger plan` uses it by default: 5 fingers x 5 links of 2 cm
    on the rim of a 3 cm palm, links of radius 4 mm, no limits."""
    hand = Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03, palm_thickness=0.01)
    hand.name = "paper_5x5"
    return hand


PRESETS: dict[str, Preset] = {p.name: p for p in (
    Preset("barrett_bh8", "BarrettHand BH8-282-like, 3x3, spread fixed at 0",
           "Barrett Technology, BH8-280/282 kinematics, joint ranges (support.barrett.com)", barrett_bh8),
    Preset("robotiq_3f", "Robotiq 3-Finger Adaptive Gripper-like, 3x3, basic mode",
           "Robotiq 3-Finger Adaptive Robot Gripper instruction manual and specifications", robotiq_3f),
    Preset("parallel_3link", "parallel gripper, two opposed 3-link fingers", "generic (no product)",
           parallel_3link),
    Preset("paper_5x5", "the paper's 5x5 rim hand (the default of hugger plan)", "Reznik & Lumelsky 1994",
           paper_5x5),
)}


def preset(name: str) -> Hand:
    """The preset hand called ``name`` (see :data:`PRESETS`); ``ValueError`` naming the presets
    for an unknown name."""
    if name not in PRESETS:
        raise ValueError(f"unknown hand preset {name!r}; the presets are {', '.join(PRESETS)}")
    return PRESETS[name].build()
