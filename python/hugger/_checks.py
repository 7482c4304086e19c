"""Argument checks shared by the package's modules: one wording for one mistake."""
from __future__ import annotations

import math
from typing import Any


def positive(name: str, value: Any, allow_zero: bool = False) -> float:
    """``value`` as a float, which must be finite and positive (or zero, with ``allow_zero``);
    otherwise a ValueError naming ``name``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(x) or x < 0 or (x == 0 and not allow_zero):
        kind = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name} must be a {kind} finite number, got {value!r}")
    return x
