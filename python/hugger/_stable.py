"""Arithmetic whose bits do not depend on the processor, for the numbers plans are made of.

NumPy chooses its loops for the processor it runs on: with AVX-512 its ``exp``, ``arccos`` or
``sin`` can differ in the last bit from those of a processor without it, and its vector norms
and matrix products go through the BLAS, whose kernels (chosen per processor too) add in their
own order and with or without fused multiply-adds. A built-in object, a start pose or an
approach direction computed so would differ between two machines, and so would every plan made
from it. These helpers use only operations IEEE 754 rounds exactly (+, -, *, /, sqrt) in a fixed
order, and for the elementary functions the C library, as the engine does.
"""
from __future__ import annotations

import math
from typing import Any, Callable, cast

import numpy as np


def _each(f: Callable[..., float], *args: Any) -> np.ndarray:
    """f of the arguments' elements, one call each (arrays of one shape)."""
    arrays = [np.asarray(x, dtype=np.float64) for x in args]
    shape = arrays[0].shape
    if any(a.shape != shape for a in arrays):
        raise ValueError(f"{f.__name__} needs arrays of one shape, got {[a.shape for a in arrays]}")
    out = map(f, *(a.ravel().tolist() for a in arrays))
    return np.fromiter(out, dtype=np.float64, count=arrays[0].size).reshape(shape)


def sin(x: Any) -> np.ndarray:
    """Elementwise sine (the C library's)."""
    return _each(math.sin, x)


def cos(x: Any) -> np.ndarray:
    """Elementwise cosine (the C library's)."""
    return _each(math.cos, x)


def exp(x: Any) -> np.ndarray:
    """Elementwise exponential (the C library's)."""
    return _each(math.exp, x)


def arccos(x: Any) -> np.ndarray:
    """Elementwise arc cosine (the C library's); arguments in [-1, 1]."""
    return _each(math.acos, x)


def arctan2(y: Any, x: Any) -> np.ndarray:
    """Elementwise atan2(y, x) (the C library's) of two arrays of one shape."""
    return _each(math.atan2, y, x)


def dot(a: Any, b: Any) -> np.ndarray:
    """a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + ... along the last axis, added left to right
    (a NumPy float for two vectors)."""
    x, y = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    if x.ndim == 0 or x.shape[-1] == 0:
        raise ValueError(f"dot needs vectors along the last axis, got shape {x.shape}")
    s = x[..., 0] * y[..., 0]
    for i in range(1, x.shape[-1]):
        s = s + x[..., i] * y[..., i]
    return cast(np.ndarray, s)


def norm(v: Any) -> np.ndarray:
    """Euclidean norm along the last axis, sqrt(x0*x0 + x1*x1 + ...) added left to right (a
    NumPy float for a vector)."""
    return cast(np.ndarray, np.sqrt(dot(v, v)))


def farthest(points: Any, centre: Any) -> float:
    """The largest distance of the points (k, 3) from ``centre`` (3,): an object's radius about T."""
    return float(norm(np.asarray(points, dtype=np.float64) - np.asarray(centre, dtype=np.float64)).max())


def matmul(a: Any, b: Any) -> np.ndarray:
    """The matrix product a @ b, each entry's terms added left to right: 2-D arrays, or a vector
    on either side (as ``@`` takes it)."""
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if x.ndim == 1 and y.ndim >= 1:
        return cast(np.ndarray, matmul(x[None], y)[0])
    if y.ndim == 1 and x.ndim >= 1:
        return matmul(x, y[:, None])[:, 0]
    if x.ndim != 2 or y.ndim != 2 or x.shape[1] != y.shape[0] or x.shape[1] == 0:
        raise ValueError(f"matmul needs 2-D arrays (or vectors) with matching inner sizes, got {x.shape} and {y.shape}")
    out = x[:, :1] * y[:1, :]
    for k in range(1, x.shape[1]):
        out = out + x[:, k:k + 1] * y[k:k + 1, :]
    return out
