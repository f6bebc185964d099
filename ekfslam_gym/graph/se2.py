"""SE(2) helpers: poses as vectors (x, y, θ) [m, m, rad], homogeneous transforms, the odometry model.

All functions accept a single pose of shape (3,) or a stack of shape (..., 3) and broadcast.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..angles import wrap_angles

__all__ = [
    "between",
    "compose",
    "inverse",
    "odometry_jacobian",
    "odometry_to_relative",
    "t2v",
    "v2t",
    "wheels_jacobian",
    "wheels_to_relative",
]


def v2t(pose: ArrayLike) -> NDArray[np.float64]:
    """Homogeneous 3×3 transform(s) of pose vector(s) (x, y, θ)."""
    p = np.asarray(pose, dtype=float)
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    T = np.zeros(p.shape[:-1] + (3, 3))
    T[..., 0, 0], T[..., 0, 1], T[..., 0, 2] = c, -s, p[..., 0]
    T[..., 1, 0], T[..., 1, 1], T[..., 1, 2] = s, c, p[..., 1]
    T[..., 2, 2] = 1.0
    return T


def t2v(T: ArrayLike) -> NDArray[np.float64]:
    """Pose vector(s) (x, y, θ) of homogeneous transform(s); θ = atan2(R₂₁, R₁₁) lies in [−π, π]."""
    M = np.asarray(T, dtype=float)
    return np.stack([M[..., 0, 2], M[..., 1, 2], np.arctan2(M[..., 1, 0], M[..., 0, 0])], axis=-1)


def compose(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """a ⊕ b: pose b, given in the frame of a, expressed in a's parent frame (heading wrapped)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack(
        [
            a[..., 0] + c * b[..., 0] - s * b[..., 1],
            a[..., 1] + s * b[..., 0] + c * b[..., 1],
            wrap_angles(a[..., 2] + b[..., 2]),
        ],
        axis=-1,
    )


def inverse(a: ArrayLike) -> NDArray[np.float64]:
    """⊖a, so that compose(a, inverse(a)) is the identity."""
    a = np.asarray(a, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack(
        [-c * a[..., 0] - s * a[..., 1], s * a[..., 0] - c * a[..., 1], wrap_angles(-a[..., 2])], axis=-1
    )


def between(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """a⁻¹ b: pose b seen from pose a (the relative-pose measurement of a pose-pose edge)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy, wrap_angles(b[..., 2] - a[..., 2])], axis=-1)


def odometry_to_relative(odometry: ArrayLike) -> NDArray[np.float64]:
    """Relative pose (in the frame of the pose before the step) of odometry controls (r1, t, r2).

    The odometry model rotates by r1, drives t straight ahead, then rotates by r2.
    """
    u = np.asarray(odometry, dtype=float)
    r1, t, r2 = u[..., 0], u[..., 1], u[..., 2]
    return np.stack([t * np.cos(r1), t * np.sin(r1), wrap_angles(r1 + r2)], axis=-1)


def odometry_jacobian(odometry: ArrayLike) -> NDArray[np.float64]:
    """V = ∂(relative pose)/∂(r1, t, r2), shape (..., 3, 3); its determinant is −t."""
    u = np.asarray(odometry, dtype=float)
    r1, t = u[..., 0], u[..., 1]
    c, s = np.cos(r1), np.sin(r1)
    V = np.zeros(u.shape[:-1] + (3, 3))
    V[..., 0, 0], V[..., 0, 1] = -t * s, c
    V[..., 1, 0], V[..., 1, 1] = t * c, s
    V[..., 2, 0], V[..., 2, 2] = 1.0, 1.0
    return V


def _sinc_and_derivative(u: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """sin(u)/u and its derivative, elementwise and smooth through u = 0 (series below 1e-4)."""
    small = np.abs(u) < 1e-4
    safe = np.where(small, 1.0, u)
    u2 = u * u
    sinc = np.where(small, 1.0 - u2 / 6.0 + u2 * u2 / 120.0, np.sin(safe) / safe)
    derivative = np.where(
        small, -u / 3.0 + u * u2 / 30.0, (safe * np.cos(safe) - np.sin(safe)) / (safe * safe)
    )
    return sinc, derivative


def wheels_to_relative(odometry: ArrayLike, wheel_base: float) -> NDArray[np.float64]:
    """Relative pose (in the frame of the pose before the step) of wheel odometry (left, right, slip) [m]: the
    wheels' arc, turn a = (right - left) / b and chord (left + right) / 2 sinc(a / 2) along the mid-heading a / 2,
    plus the sideways slip along its normal (the filter's wheels model, Thrun, Burgard & Fox, section 5.3)."""
    u = np.asarray(odometry, dtype=float)
    left, right, slip = u[..., 0], u[..., 1], u[..., 2]
    half = 0.5 * (right - left) / wheel_base
    sinc, _ = _sinc_and_derivative(half)
    chord = 0.5 * (left + right) * sinc
    c, s = np.cos(half), np.sin(half)
    return np.stack([chord * c - slip * s, chord * s + slip * c, wrap_angles(2.0 * half)], axis=-1)


def wheels_jacobian(odometry: ArrayLike, wheel_base: float) -> NDArray[np.float64]:
    """∂(relative pose)/∂(left, right, slip) of ``wheels_to_relative``, shape (..., 3, 3)."""
    u = np.asarray(odometry, dtype=float)
    left, right, slip = u[..., 0], u[..., 1], u[..., 2]
    half = 0.5 * (right - left) / wheel_base
    sinc, dsinc = _sinc_and_derivative(half)
    d = 0.5 * (left + right)
    chord = d * sinc
    c, s = np.cos(half), np.sin(half)
    dhalf = np.array([-0.5, 0.5]) / wheel_base  # ∂half/∂(left, right)
    J = np.zeros(u.shape[:-1] + (3, 3))
    for k in range(2):  # left, right
        dchord = 0.5 * sinc + d * dsinc * dhalf[k]
        J[..., 0, k] = dchord * c - (chord * s + slip * c) * dhalf[k]
        J[..., 1, k] = dchord * s + (chord * c - slip * s) * dhalf[k]
        J[..., 2, k] = 2.0 * dhalf[k]
    J[..., 0, 2] = -s
    J[..., 1, 2] = c
    return J
