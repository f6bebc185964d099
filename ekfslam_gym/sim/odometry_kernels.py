"""Compiled odometry kernels: the exact turn-drive-turn decomposition of a planar motion, the alpha noise model
of Thrun, Burgard & Fox (*Probabilistic Robotics*, table 5.6) and the arc (velocity) form, plus the noisy
readings built from them. ``ekfslam_gym.sim.odometry`` wraps them for Python; other kernels call them directly.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..angles import compiled_wrap_angle as wrap_angle
from ..kernel_types import F8Array1, F8Array2

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
    alphas: F8Array1,
    normals: F8Array1,
    u: F8Array1,
    cov: F8Array2,
    u_true: F8Array1,
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
    alphas: F8Array1,
    normals: F8Array1,
    u: F8Array1,
    cov: F8Array2,
    u_true: F8Array1,
) -> None:
    """The velocity form of ``odometry_reading``: the arc's (v, omega) plus std * normals, N = diag(std^2)."""
    u_true[0], u_true[1] = velocity_from_motion(x0, y0, theta0, x1, y1, theta1, dt)
    std = velocity_std(u_true[0], u_true[1], alphas)
    for i in range(2):
        u[i] = u_true[i] + std[i] * normals[i]
        cov[i, i] = std[i] * std[i]


@njit(cache=True)
def decompose_wheels(
    x0: float, y0: float, theta0: float, x1: float, y1: float, theta1: float, wheel_base: float
) -> tuple[float, float, float]:
    """The (left, right, slip) wheel travels and sideways slip (m) that take pose 0 exactly to pose 1.

    The inverse of ``ekfslam_gym.filter.models.wheel_motion``: the turn a = theta1 - theta0 (unwrapped), the
    displacement split along the mid-heading theta0 + a/2 into a forward part f (the arc's chord, so the arc
    length is d = f / sinc(a/2)) and a sideways part, the slip; left = d - b a / 2, right = d + b a / 2. In free
    space the slip is the small residual of a step that is not one arc (a command change inside it); sliding
    along a wall it is most of the motion. Valid for |a| < 2 pi (a step turns at most omega_max dt).
    """
    a = theta1 - theta0
    half = 0.5 * a
    c_mid = math.cos(theta0 + half)
    s_mid = math.sin(theta0 + half)
    dx = x1 - x0
    dy = y1 - y0
    forward = dx * c_mid + dy * s_mid
    slip = -dx * s_mid + dy * c_mid
    sinc = 1.0 - half * half / 6.0 if abs(half) < 1e-4 else math.sin(half) / half
    d = forward / sinc
    return d - 0.5 * wheel_base * a, d + 0.5 * wheel_base * a, slip


@njit(cache=True)
def wheel_std(
    left: float, right: float, contact_travel: float, params: np.ndarray
) -> tuple[float, float, float]:
    """Standard deviations (m) of the noise on (left, right, slip); ``params`` is ``WheelOdometryNoise.vector``
    (wheel_alpha, wheel_floor, slip_floor, slip_contact, slide_sensed).

    Each wheel's error grows with its own travel plus a floor; the slip's with ``contact_travel``, the distance
    the robot was commanded to drive in a step in contact with a wall (0 without contact), plus a floor."""
    return (
        params[0] * abs(left) + params[1],
        params[0] * abs(right) + params[1],
        params[2] + params[3] * contact_travel,
    )


@njit(cache=True)
def wheel_reading(
    trace: F8Array2,
    wheel_base: float,
    contact_travel: float,
    params: F8Array1,
    normals: F8Array1,
    u: F8Array1,
    cov: F8Array2,
    u_true: F8Array1,
) -> None:
    """Wheel odometry over one step whose poses after each substep are ``trace`` (S+1, 3), the step's start
    pose first, written into ``u``, ``cov`` (M = diag(std^2); zeros off the diagonal are the caller's) and
    ``u_true`` (the true motion's decomposition), as ``odometry_reading`` does.

    Slide sensed (``params[4]`` = 1): u = u_true + std * normals (3 normals), exactly the reported covariance.
    Not sensed: the wheels integrated at the substep rate, each substep's motion projected on its own
    mid-heading (what the wheels roll; a sideways slide they cannot see) and chained. In free space each
    substep is an exact arc, so this is the true motion even when the command changed within the step (two
    arcs, whose residual against one arc is a few millimetres of slip); in contact the slide is missing. The
    chained motion as (left, right, slip), the wheel travels plus std * normals[:2], is the reading, and M[2, 2]
    only the modelled variance of the missing slide."""
    last = trace.shape[0] - 1
    if params[4] != 0.0:
        sensed_wheel_reading(
            trace[0, 0], trace[0, 1], trace[0, 2], trace[last, 0], trace[last, 1], trace[last, 2], wheel_base,
            contact_travel, params, normals, u, cov, u_true,
        )  # fmt: skip
        return
    u_true[0], u_true[1], u_true[2] = decompose_wheels(
        trace[0, 0], trace[0, 1], trace[0, 2], trace[last, 0], trace[last, 1], trace[last, 2], wheel_base
    )
    x = trace[0, 0]
    y = trace[0, 1]
    for i in range(1, last + 1):
        mid = 0.5 * (trace[i - 1, 2] + trace[i, 2])
        c = math.cos(mid)
        s = math.sin(mid)
        forward = (trace[i, 0] - trace[i - 1, 0]) * c + (trace[i, 1] - trace[i - 1, 1]) * s
        x += forward * c
        y += forward * s
    u[0], u[1], u[2] = decompose_wheels(
        trace[0, 0], trace[0, 1], trace[0, 2], x, y, trace[last, 2], wheel_base
    )
    _add_wheel_noise(contact_travel, params, normals, u, cov)


@njit(cache=True)
def sensed_wheel_reading(
    x0: float,
    y0: float,
    theta0: float,
    x1: float,
    y1: float,
    theta1: float,
    wheel_base: float,
    contact_travel: float,
    params: np.ndarray,
    normals: np.ndarray,
    u: np.ndarray,
    cov: np.ndarray,
    u_true: np.ndarray,
) -> None:
    """``wheel_reading`` with the slide sensed (``params[4]`` = 1), from the step's start and end poses as
    scalars: the same values, without building the (2, 3) trace array (the env's hot path)."""
    u_true[0], u_true[1], u_true[2] = decompose_wheels(x0, y0, theta0, x1, y1, theta1, wheel_base)
    u[0] = u_true[0]
    u[1] = u_true[1]
    u[2] = u_true[2]
    _add_wheel_noise(contact_travel, params, normals, u, cov)


@njit(cache=True)
def _add_wheel_noise(
    contact_travel: float, params: np.ndarray, normals: np.ndarray, u: np.ndarray, cov: np.ndarray
) -> None:
    """u += std * normals (the slip only when the slide is sensed) and cov's diagonal = std^2, std from u."""
    std = wheel_std(u[0], u[1], contact_travel, params)
    for i in range(3):
        if i < 2 or params[4] != 0.0:
            u[i] += std[i] * normals[i]
        cov[i, i] = std[i] * std[i]
