"""The colours of a plan's pictures, written once: the figures and animations (:mod:`hugger.viz`,
matplotlib: hex strings and RGB fractions) and the 3D viewer and glTF scene (:mod:`hugger.viewer`,
RGB 0..255 through :func:`rgb255`)."""
from __future__ import annotations

from typing import Sequence

#: The TipStates FROZEN, CONTACT, DONE: blue, orange, green.
STATE_COLORS = ("#3b6fb6", "#e8842c", "#2e9e4f")
#: The object and the palm (RGB fractions).
OBJECT_RGB = (0.82, 0.75, 0.66)
PALM_RGB = (0.50, 0.50, 0.55)
#: The contact dots.
CONTACT_COLOR = "#d62728"


def rgb255(color: str | Sequence[float]) -> tuple[int, int, int]:
    """``color``, a ``"#rrggbb"`` string or RGB fractions, as RGB 0..255 (fractions rounded)."""
    if isinstance(color, str):
        r, g, b = (int(color[i:i + 2], 16) for i in (1, 3, 5))
    else:
        r, g, b = (int(round(255 * c)) for c in color)
    return r, g, b
