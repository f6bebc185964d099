"""Angle wrapping, the one convention used everywhere: (-pi, pi], so +pi stays +pi and -pi becomes +pi.

``wrap_angle`` is plain Python, so the env's start-up never loads numba; the compiled kernels use
``compiled_wrap_angle``, the same function compiled by numba on first use.
"""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_angle(angle: float) -> float:
    """Wrap one angle in radians to (-pi, pi]."""
    wrapped = math.pi - (math.pi - angle) % TWO_PI
    if wrapped <= -math.pi:
        wrapped += TWO_PI
    return wrapped


def wrap_angles(angles) -> np.ndarray:
    """Wrap an array of angles in radians to (-pi, pi] (the same values as ``wrap_angle``, element-wise)."""
    wrapped = np.pi - np.mod(np.pi - np.asarray(angles, dtype=float), TWO_PI)
    return np.where(wrapped <= -np.pi, wrapped + TWO_PI, wrapped)


def __getattr__(name: str):
    if name == "compiled_wrap_angle":
        from numba import njit

        compiled = njit(cache=True)(wrap_angle)
        globals()[name] = compiled
        return compiled
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
