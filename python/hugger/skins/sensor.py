"""A skin with a sensor model: range, Gaussian noise and taxels on top of any skin.

The model stays *safe*: every gap it reports is a lower bound of the true gap of the part it was
asked about (docs/skins.md says why), so the planner, which never moves a part farther than its
sensed gap, stays collision-free against the true object whatever the settings:

- ``range`` (m): nothing is felt beyond it. A part farther than ``range`` from the object is
  reported at a gap of exactly ``range`` ("nothing within range"), never farther.
- ``gap_noise`` (m): Gaussian noise of that standard deviation on every gap, truncated at 3
  standard deviations, after a calibration offset of -3 standard deviations (the reading never
  exceeds the true gap). ``normal_noise`` (rad): the reported normal is tilted by a Gaussian
  angle of that standard deviation (truncated at 3) about a random axis.
- ``taxel_spacing`` (m): the link's skin is a row of taxels along its axis, at most that far
  apart (both ends included). Each taxel senses the ball about it that covers its share of the
  capsule, of radius sqrt(radius^2 + (spacing/2)^2); the link reports its nearest taxel's gap and
  that taxel as the point of contact, not the exact nearest point.

Noise comes from one ``numpy.random.Generator`` seeded by ``seed``, drawn in query order: the
planner's queries are deterministic, so a plan is too (bit-identical for the same input).
"""
from __future__ import annotations

import math
from typing import Any, cast

import numpy as np

from .._checks import shown, whole
from .._core import Sensing, Touch


def _setting(name: str, value: Any, allow_inf: bool = False) -> float:
    v = float(value)
    if math.isnan(v) or v < 0 or (math.isinf(v) and not allow_inf):
        raise ValueError(f"{name} must be a number >= 0{' or inf' if allow_inf else ''}, got {shown(value)}")
    return v


class SensorModel(Sensing):
    """Wraps ``skin`` (any :class:`hugger.skins.Sensing`, or a :class:`hugger.Object`, sensed by
    its mesh world) with a sensing ``range``, ``gap_noise``, ``normal_noise`` and
    ``taxel_spacing``; ``seed`` fixes the noise. Counts its queries in ``queries``."""

    #: Its answers depend on the queries before them (one noise stream): hugger.plan_many plans the
    #: cases that share one such skin one after another, in input order.
    keeps_state = True

    def __init__(self, skin: Any, range: float = math.inf, gap_noise: float = 0.0, normal_noise: float = 0.0,  # noqa: A002
                 taxel_spacing: float | None = None, seed: int = 0) -> None:
        super().__init__()
        from ..world import Object
        from .mesh import MeshSkin, recorded_object

        #: The Object given as the skin (sensed through its mesh world), or that of a MeshSkin or
        #: SensorModel given, else None: a planner records it with the plan unless given another
        #: ``record_object``.
        self.object: Object | None = skin if isinstance(skin, Object) else recorded_object(skin)
        if isinstance(skin, Object):
            skin = MeshSkin(skin)
        if not isinstance(skin, Sensing):
            raise ValueError(f"skin must be a hugger Sensing skin or Object, got {type(skin).__name__}")
        self.skin = skin
        self.range = _setting("range", range, allow_inf=True)
        if self.range == 0:
            raise ValueError("range must be positive (m)")
        self.gap_noise = _setting("gap_noise", gap_noise)
        self.normal_noise = _setting("normal_noise", normal_noise)
        self.taxel_spacing = None if taxel_spacing is None else _setting("taxel_spacing", taxel_spacing)
        if self.taxel_spacing == 0:
            raise ValueError("taxel_spacing must be positive (m) or None")
        self.seed = whole("seed", seed, 0)
        self._rng = np.random.default_rng(self.seed)
        self.queries = 0

    def uncertainty(self, radius: float) -> float:
        """How much a reading may under-report the true gap of a link of ``radius`` (m), within
        the range: 6 standard deviations of gap noise plus, with taxels, how far a taxel's ball
        reaches beyond the capsule. The planner needs a ``contact_tolerance`` of a few times this
        (``bench/sensor_sweep.py`` uses 4x): below it, readings that scatter by more than the
        clinging tolerance (contact_tolerance / 8) stop the fingers early."""
        excess = 0.0
        if self.taxel_spacing is not None:
            excess = math.hypot(radius, 0.5 * self.taxel_spacing) - radius
        return 6.0 * self.gap_noise + excess

    def _noise(self, sigma: float) -> float:
        if sigma == 0.0:
            return 0.0
        return sigma * float(np.clip(self._rng.standard_normal(), -3.0, 3.0))

    def _ask(self, cap: float) -> float:
        """The cap to ask the skin under the model with, for a reading exact up to ``cap``: a
        reading lies up to 6 standard deviations below the true gap, so a true gap beyond this
        reads above ``cap`` (and above the range, which is the most the model reports)."""
        return min(cap, self.range) + 6.0 * self.gap_noise

    def _reading(self, gap: float) -> float:
        """A sensed gap: noisy, calibrated to stay at or below the true gap, cut at the range."""
        if self.gap_noise > 0.0 and math.isfinite(gap):
            gap = gap - 3.0 * self.gap_noise + self._noise(self.gap_noise)
        return min(gap, self.range)

    def _tilt(self, normal: np.ndarray) -> np.ndarray:
        if self.normal_noise == 0.0:
            return normal
        angle = self._noise(self.normal_noise)
        axis = np.cross(normal, self._rng.standard_normal(3))
        norm = np.linalg.norm(axis)
        if norm < 1e-12:
            return normal
        axis /= norm
        # Rodrigues: normal is perpendicular to axis.
        return math.cos(angle) * normal + math.sin(angle) * np.cross(axis, normal)

    def capsule(self, a: np.ndarray, b: np.ndarray, radius: float, cap: float = math.inf) -> Touch:  # type: ignore[override]
        self.queries += 1
        ask = self._ask(cap)
        t: Touch | None
        if self.taxel_spacing is None:
            t = self.skin.capsule(a, b, radius, ask)
        else:
            length = float(np.linalg.norm(b - a))
            n = max(1, math.ceil(length / self.taxel_spacing))
            half = 0.5 * length / n
            ball = math.hypot(radius, half) if n > 1 or length > 0 else radius
            t = None
            for s in np.linspace(0.0, 1.0, n + 1) if length > 0 else (0.0,):
                p = a + s * (b - a)
                u = self.skin.capsule(p, p, ball, ask)
                if t is None or u.gap < t.gap:
                    t = u
            t = cast(Touch, t)  # the loop runs at least once
        gap = self._reading(t.gap)
        if not math.isfinite(t.gap) or t.gap > self.range:  # nothing felt: no contact point either
            return Touch(gap, t.on_hand, t.on_hand, t.normal)
        return Touch(gap, t.on_hand, t.on_object, self._tilt(np.asarray(t.normal)))

    def palm(self, pose: np.ndarray, radius: float, thickness: float, cap: float = math.inf) -> float:  # type: ignore[override]
        self.queries += 1
        return self._reading(float(self.skin.palm(pose, radius, thickness, self._ask(cap))))
