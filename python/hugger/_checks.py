"""Argument checks shared by the package's modules: one wording for one mistake."""
from __future__ import annotations

import math
import numbers
import os
from typing import Any

import numpy as np


def shown(value: Any) -> str:
    """``value`` as the messages show it: its repr, but a NumPy number (or a 0-d array) as the
    number it holds: ``-0.1``, not ``np.float64(-0.1)``; a float32 at its own precision."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, np.floating):
        return str(value)  # (item() would widen a float32: -0.10000000149011612)
    return repr(value.item() if isinstance(value, np.generic) else value)


def number(name: str, value: Any) -> float:
    """``value`` as a float (any sign, not checked for finiteness); otherwise a ValueError naming
    ``name``. Text and bools are not numbers here (``float`` reads "0.04" and True as 1)."""
    if isinstance(value, (str, bytes, bool, np.bool_)):
        raise ValueError(f"{name} must be a number, got {shown(value)}")
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a number, got {shown(value)}") from None


def positive(name: str, value: Any, allow_zero: bool = False, most: float | None = None,
             least: float | None = None) -> float:
    """``value`` as a float (:func:`number`), which must be finite and positive (or zero, with
    ``allow_zero``), at least ``least`` and at most ``most`` (each if given); otherwise a
    ValueError naming ``name``."""
    x = number(name, value)
    if not math.isfinite(x) or x < 0 or (x == 0 and not allow_zero):
        kind = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name} must be a {kind} finite number, got {shown(value)}")
    if most is not None and x > most:
        raise ValueError(f"{name} must be at most {most:g}, got {shown(value)}")
    if least is not None and x < least:
        raise ValueError(f"{name} must be at least {least:g}, got {shown(value)}")
    return x


def real_array(name: str, value: Any) -> np.ndarray:
    """``value`` as a float64 array; ``ValueError`` for strings, complex, booleans or objects
    that are not numbers (numpy would otherwise cast them silently or with a warning)."""
    if value is None:
        raise ValueError(f"{name} must be an array of real numbers, got None")
    try:
        a = np.asarray(value)
    except (TypeError, ValueError, OverflowError, RecursionError):
        raise ValueError(f"{name} must be an array of real numbers") from None
    if a.dtype.kind == "O":
        if any(x is None for x in a.flat):  # numpy would turn None into nan
            raise ValueError(f"{name} must be an array of real numbers, got None in it")
        try:
            a = a.astype(np.float64)
        except (TypeError, ValueError, OverflowError):
            raise ValueError(f"{name} must be an array of real numbers, got Python objects") from None
    if a.dtype.kind in "USb":  # (numpy would read "0.04" as a number, and True as 1)
        raise ValueError(f"{name} must be an array of real numbers, got {'booleans' if a.dtype.kind == 'b' else 'text'}")
    if a.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be an array of real numbers, got dtype {a.dtype}")
    with np.errstate(over="ignore"):
        return a.astype(np.float64)


def whole(name: str, value: Any, lo: int | None = None, hi: int | None = None) -> int:
    """``value`` as an int: a whole number (an integer type, not a bool) from ``lo`` to ``hi``
    (either may be None: unbounded); otherwise a ValueError naming ``name``."""
    ok = not isinstance(value, bool) and isinstance(value, numbers.Integral)
    if ok and (lo is None or value >= lo) and (hi is None or value <= hi):
        return int(value)
    if lo is not None and hi is not None:
        rule = f"a whole number from {lo} to {hi}"
    elif lo is not None:
        rule = f"a whole number >= {lo}"
    elif hi is not None:
        rule = f"a whole number <= {hi}"
    else:
        rule = "a whole number"
    raise ValueError(f"{name} must be {rule}, got {shown(value)}")


def flag(name: str, value: Any) -> bool:
    """``value`` as a bool: True or False (a NumPy bool too); otherwise a ValueError naming ``name``."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {shown(value)}")
    return bool(value)


def callback(name: str, value: Any, call: str) -> None:
    """A ValueError naming ``name`` unless ``value`` is None or callable (as ``call`` shows)."""
    if value is not None and not callable(value):
        raise ValueError(f"{name} must be callable as {call}, or None, got {value!r}")


def cpus() -> int:
    """The CPUs this process may run on (all of them where the OS cannot say)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def workers(name: str, value: Any) -> int:
    """A count of threads or processes: a whole number >= 1, or None for :func:`cpus`."""
    if value is None:
        return cpus()
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise ValueError(f"{name} must be a whole number >= 1 or None, got {shown(value)}")
    return int(value)
