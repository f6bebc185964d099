"""Angle wrapping, the one convention used everywhere: (-pi, pi], so +pi stays +pi and -pi becomes +pi."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

TWO_PI = 2.0 * math.pi


@njit(cache=True)
def wrap_angle(angle: float) -> float:
    """Wrap one angle in radians to (-pi, pi] (compiled, so kernels can call it)."""
    wrapped = math.pi - (math.pi - angle) % TWO_PI
    if wrapped <= -math.pi:
        wrapped += TWO_PI
    return wrapped


def wrap_angles(angles) -> np.ndarray:
    """Wrap an array of angles in radians to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(angles, dtype=float), TWO_PI)
