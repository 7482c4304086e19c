"""Types and constants shared by the package's modules (imported by them, importing none of them but
the compiled engine, which owns the hand-size limits).

:class:`TipState` is the state of a finger in a plan (``tip_state`` in a trajectory file, int8),
:class:`Configuration` one hand configuration of a plan; the constants are the hand-size limits
(checked by :class:`hugger.Hand` and by the file reader) and the gap that counts as a touch in
summaries, analysis, figures and the physics squeeze.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from . import _core

#: The package version (hugger.__version__), recorded in trajectory files and dataset indexes.
VERSION = "0.1.0"
#: Largest number of fingers M and of links per finger N. The engine checks every pair of
#: fingers each iteration (O(M^2 N^2)), so a plan with more fingers would be unusably slow; the
#: limits are checked before anything is allocated, so ``Hand(fingers=10**6)`` fails at once.
#: The engine owns them (kMaxFingers, kMaxLinks in hugger/hand/hand_model.hpp).
MAX_FINGERS: int = _core.MAX_FINGERS
MAX_LINKS: int = _core.MAX_LINKS

#: Gap (m) at or below which a link or the palm counts as touching O, in summaries, analysis,
#: figures and the physics squeeze.
CONTACT_DISTANCE = 1e-3


class TipState(enum.IntEnum):
    """State of a finger (docs/model.md): open and not yet sensing the object, closing on it, finished."""

    FROZEN = 0
    CONTACT = 1
    DONE = 2


FROZEN, CONTACT, DONE = TipState.FROZEN, TipState.CONTACT, TipState.DONE


@dataclass(frozen=True)
class Configuration:
    """One hand configuration (docs/model.md)."""

    palm_pose: np.ndarray  #: (4, 4) T_WP
    joints: np.ndarray  #: (M, N+1, 3) joint positions in the world, j_m0 (tail) .. j_mN (tip)
    angles: np.ndarray  #: (M, N) joint angles (rad), positive = flexion
    tip_state: np.ndarray  #: (M,) int8: 0 FROZEN, 1 CONTACT, 2 DONE
    phase: int  #: 0 for C_init, then 1 (reorientation) or 2 (approach and hugging)
    iteration: int  #: index of this configuration in the plan
