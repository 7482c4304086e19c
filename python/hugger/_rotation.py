"""Rotation helpers shared by the MJCF writer, the viewer, the robot-file import and export and
the baseline (numpy only)."""
from __future__ import annotations

import math
from typing import cast

import numpy as np

from . import _stable


def quaternion_wxyz(rot: np.ndarray) -> np.ndarray:
    """The unit quaternion (w, x, y, z) of a rotation matrix (3, 3), by Shepperd's method."""
    r = np.asarray(rot, dtype=np.float64)
    t = np.trace(r)
    if t > 0:
        s = math.sqrt(t + 1.0) * 2
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2]) * 2
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif r[1, 1] > r[2, 2]:
        s = math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2]) * 2
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1]) * 2
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    quat = np.array(q)
    return cast(np.ndarray, quat / _stable.norm(quat))


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation matrix (3, 3) turning by ``angle`` (rad) about ``axis`` (any length but zero),
    by Rodrigues' formula."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / _stable.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return cast(np.ndarray, np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * _stable.matmul(k, k))
