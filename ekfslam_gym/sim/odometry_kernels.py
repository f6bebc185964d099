"""Compiled odometry kernels: the exact turn-drive-turn decomposition of a planar motion, the alpha noise model
of Thrun, Burgard & Fox (*Probabilistic Robotics*, table 5.6) and the arc (velocity) form, plus the noisy
readings built from them. ``ekfslam_gym.sim.odometry`` wraps them for Python; other kernels call them directly.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..angles import compiled_wrap_angle as wrap_angle

HALF_PI = 0.5 * math.pi


@njit(cache=True)
def decompose_odometry(
    x0: float, y0: float, theta0: float, x1: float, y1: float, theta1: float, min_trans: float = 1e-9
) -> tuple[float, float, float]:
    """The (rot1, trans, rot2) that takes pose 0 exactly to pose 1.

    x1 = x0 + trans cos(theta0 + rot1), y1 = y0 + trans sin(theta0 + rot1), theta1 = theta0 + rot1 + rot2.
    Backward motion is a negative ``trans`` with |rot1| <= pi/2 rather than rot1 near pi, so reversing does not
    look like two half-turns (whose alpha noise would be huge). Below ``min_trans`` metres the direction of
    travel is undefined: rot1 = 0 and the whole turn goes into rot2.
    """
    dx = x1 - x0
    dy = y1 - y0
    trans = math.sqrt(dx * dx + dy * dy)
    if trans < min_trans:
        rot1 = 0.0
    else:
        rot1 = wrap_angle(math.atan2(dy, dx) - theta0)
        if rot1 > HALF_PI:
            rot1 -= math.pi
            trans = -trans
        elif rot1 < -HALF_PI:
            rot1 += math.pi
            trans = -trans
    rot2 = (theta1 - theta0) - rot1
    return rot1, trans, rot2


@njit(cache=True)
def odometry_std(rot1: float, trans: float, rot2: float, alphas: np.ndarray) -> tuple[float, float, float]:
    """Standard deviations (rad, m, rad) of the noise on (rot1, trans, rot2); ``alphas`` is
    ``OdometryNoise.vector`` (alpha1..alpha4, rot_floor, trans_floor)."""
    a_rot1 = abs(rot1)
    a_trans = abs(trans)
    a_rot2 = abs(rot2)
    return (
        alphas[0] * a_rot1 + alphas[1] * a_trans + alphas[4],
        alphas[2] * a_trans + alphas[3] * (a_rot1 + a_rot2) + alphas[5],
        alphas[0] * a_rot2 + alphas[1] * a_trans + alphas[4],
    )


@njit(cache=True)
def odometry_reading(
    x0: float,
    y0: float,
    theta0: float,
    x1: float,
    y1: float,
    theta1: float,
    alphas: np.ndarray,
    normals: np.ndarray,
    u: np.ndarray,
    cov: np.ndarray,
    u_true: np.ndarray,
) -> None:
    """Write u (the exact decomposition plus std * normals), M = diag(std^2) into ``cov`` (zeros off the
    diagonal are the caller's) and the exact decomposition into ``u_true``: the caller allocates, because
    arrays made inside a compiled function cost more to hand back to Python than the arithmetic."""
    u_true[0], u_true[1], u_true[2] = decompose_odometry(x0, y0, theta0, x1, y1, theta1)
    std = odometry_std(u_true[0], u_true[1], u_true[2], alphas)
    for i in range(3):
        u[i] = u_true[i] + std[i] * normals[i]
        cov[i, i] = std[i] * std[i]


@njit(cache=True)
def velocity_from_motion(
    x0: float, y0: float, theta0: float, x1: float, y1: float, theta1: float, dt: float
) -> tuple[float, float]:
    """The (v m/s, omega rad/s) of the circular arc that ends at pose 1's heading and travels its chord.

    omega = dtheta / dt and v = chord / (dt sinc(dtheta / 2)), signed by the direction of travel, which is the
    inverse of the chord form x1 = x0 + v dt sinc(a/2) cos(theta0 + a/2), a = omega dt. Only approximate: the
    true motion over a step is not exactly an arc (its chord need not point along theta0 + a/2, e.g. when a wall
    deflects the robot), and that residual is *not* in the reported covariance. Prefer the odometry model when
    consistency matters.
    """
    dtheta = theta1 - theta0
    dx = x1 - x0
    dy = y1 - y0
    chord = math.sqrt(dx * dx + dy * dy)
    half = 0.5 * dtheta
    sinc = 1.0 - half * half / 6.0 if abs(half) < 1e-4 else math.sin(half) / half
    mid = theta0 + half
    if dx * math.cos(mid) + dy * math.sin(mid) < 0.0:
        chord = -chord
    return chord / (dt * sinc), dtheta / dt


@njit(cache=True)
def velocity_std(v: float, omega: float, alphas: np.ndarray) -> tuple[float, float]:
    """Standard deviations (m/s, rad/s) of the noise on (v, omega); ``alphas`` is ``VelocityNoise.vector``
    (alpha1..alpha4, v_floor, omega_floor), the velocity form of the alpha model (Thrun et al., table 5.3)."""
    a_v = abs(v)
    a_w = abs(omega)
    return alphas[0] * a_v + alphas[1] * a_w + alphas[4], alphas[2] * a_v + alphas[3] * a_w + alphas[5]


@njit(cache=True)
def velocity_reading(
    x0: float,
    y0: float,
    theta0: float,
    x1: float,
    y1: float,
    theta1: float,
    dt: float,
    alphas: np.ndarray,
    normals: np.ndarray,
    u: np.ndarray,
    cov: np.ndarray,
    u_true: np.ndarray,
) -> None:
    """The velocity form of ``odometry_reading``: the arc's (v, omega) plus std * normals, N = diag(std^2)."""
    u_true[0], u_true[1] = velocity_from_motion(x0, y0, theta0, x1, y1, theta1, dt)
    std = velocity_std(u_true[0], u_true[1], alphas)
    for i in range(2):
        u[i] = u_true[i] + std[i] * normals[i]
        cov[i, i] = std[i] * std[i]
