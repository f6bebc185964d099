"""Motion and sensor models: small pure functions returning the prediction and its Jacobians together.

Every function here is compiled with numba (``cache=True``) so the filter's kernels can call them without
Python overhead; they are also plain callables from Python, which is how the finite-difference tests use them.

Conventions: a pose is ``(x, y, theta)`` in metres and radians, a landmark ``(x, y)`` in metres, a reading
``(range, bearing)`` in metres and radians in the robot frame. Angles are wrapped to ``(-pi, pi]``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..angles import compiled_wrap_angle as wrap_angle


@njit(cache=True)
def _sinc_and_derivative(u: float) -> tuple[float, float]:
    """sin(u)/u and its derivative, smooth through u = 0 (series below 1e-4)."""
    if abs(u) < 1e-4:
        u2 = u * u
        return 1.0 - u2 / 6.0 + u2 * u2 / 120.0, -u / 3.0 + u * u2 / 30.0
    s = math.sin(u)
    return s / u, (u * math.cos(u) - s) / (u * u)


@njit(cache=True)
def velocity_motion(pose: np.ndarray, v: float, omega: float, dt: float):
    """Velocity motion model (Thrun, Burgard & Fox, table 5.3; the course's y row corrected) for a constant (v, omega) over dt seconds.

    Written in the chord form x' = x + v dt sinc(a/2) cos(theta + a/2), a = omega dt, which equals the
    textbook x - v/w sin(theta) + v/w sin(theta + w dt) (and its y row +v/w cos(theta) - v/w cos(theta + w dt))
    for omega != 0 and is smooth, value and Jacobians, through omega = 0 (a straight line).

    Returns the new pose (3,), G = d pose'/d pose (3, 3) and V = d pose'/d (v, omega) (3, 2).
    """
    theta = pose[2]
    half = 0.5 * omega * dt
    s, ds = _sinc_and_derivative(half)
    c_mid = math.cos(theta + half)
    s_mid = math.sin(theta + half)
    chord = v * dt * s

    new_pose = np.empty(3)
    new_pose[0] = pose[0] + chord * c_mid
    new_pose[1] = pose[1] + chord * s_mid
    new_pose[2] = wrap_angle(theta + omega * dt)

    G = np.eye(3)
    G[0, 2] = -chord * s_mid
    G[1, 2] = chord * c_mid

    V = np.zeros((3, 2))
    V[0, 0] = dt * s * c_mid
    V[1, 0] = dt * s * s_mid
    # d/d omega through both sinc(a/2) (d half / d omega = dt/2) and the mid-heading theta + a/2.
    V[0, 1] = v * dt * 0.5 * dt * (ds * c_mid - s * s_mid)
    V[1, 1] = v * dt * 0.5 * dt * (ds * s_mid + s * c_mid)
    V[2, 1] = dt
    return new_pose, G, V


@njit(cache=True)
def odometry_motion(pose: np.ndarray, rot1: float, trans: float, rot2: float):
    """Odometry motion model (Thrun, Burgard & Fox, table 5.6): turn rot1, drive trans metres, turn rot2.

    Returns the new pose (3,), G = d pose'/d pose (3, 3) and V = d pose'/d (rot1, trans, rot2) (3, 3).
    """
    heading = pose[2] + rot1
    c = math.cos(heading)
    s = math.sin(heading)

    new_pose = np.empty(3)
    new_pose[0] = pose[0] + trans * c
    new_pose[1] = pose[1] + trans * s
    new_pose[2] = wrap_angle(pose[2] + rot1 + rot2)

    G = np.eye(3)
    G[0, 2] = -trans * s
    G[1, 2] = trans * c

    V = np.zeros((3, 3))
    V[0, 0] = -trans * s
    V[1, 0] = trans * c
    V[0, 1] = c
    V[1, 1] = s
    V[2, 0] = 1.0
    V[2, 2] = 1.0
    return new_pose, G, V


@njit(cache=True)
def wheel_motion(pose: np.ndarray, left: float, right: float, slip: float, wheel_base: float):
    """Differential-drive (wheel encoder) motion model with a lateral slip term.

    The wheels travel ``left`` and ``right`` metres on a base of ``wheel_base`` metres: the body turns
    a = (right - left) / b and travels d = (left + right) / 2 along an arc, whose chord d sinc(a/2) points along
    the mid-heading theta + a/2 (Thrun, Burgard & Fox, *Probabilistic Robotics*, section 5.3, in chord form).
    ``slip`` is a sideways displacement (m) along the mid-heading's normal, which wheels cannot measure (the
    robot sliding along a wall); the odometry reports it as 0 with a variance (docs/filter-and-graph.md, "Known limitations of the filter").
    Smooth, value and Jacobians, through a = 0; exact for any planar motion (three numbers, three dof).

    Returns the new pose (3,), G = d pose'/d pose (3, 3) and V = d pose'/d (left, right, slip) (3, 3).
    """
    theta = pose[2]
    d = 0.5 * (left + right)
    a = (right - left) / wheel_base
    half = 0.5 * a
    s, ds = _sinc_and_derivative(half)
    c_mid = math.cos(theta + half)
    s_mid = math.sin(theta + half)
    chord = d * s
    dx = chord * c_mid - slip * s_mid
    dy = chord * s_mid + slip * c_mid

    new_pose = np.empty(3)
    new_pose[0] = pose[0] + dx
    new_pose[1] = pose[1] + dy
    new_pose[2] = wrap_angle(theta + a)

    G = np.eye(3)
    G[0, 2] = -dy
    G[1, 2] = dx

    # d/d d and d/d a of (dx, dy); a enters through sinc(a/2) (d half / d a = 1/2) and the mid-heading.
    dx_dd = s * c_mid
    dy_dd = s * s_mid
    dx_da = 0.5 * (d * ds * c_mid - dy)
    dy_da = 0.5 * (d * ds * s_mid + dx)
    inv_b = 1.0 / wheel_base
    V = np.zeros((3, 3))
    V[0, 0] = 0.5 * dx_dd - inv_b * dx_da
    V[1, 0] = 0.5 * dy_dd - inv_b * dy_da
    V[2, 0] = -inv_b
    V[0, 1] = 0.5 * dx_dd + inv_b * dx_da
    V[1, 1] = 0.5 * dy_dd + inv_b * dy_da
    V[2, 1] = inv_b
    V[0, 2] = -s_mid
    V[1, 2] = c_mid
    return new_pose, G, V


@njit(cache=True)
def range_bearing(pose: np.ndarray, landmark: np.ndarray, min_range: float):
    """Expected range-bearing reading of ``landmark`` from ``pose`` and its Jacobians.

    Returns z = (range, bearing) (2,), Hx = dz/d pose (2, 3) and Hm = dz/d landmark (2, 2). The Jacobians
    divide by the range; below ``min_range`` metres they use ``min_range`` instead, so a landmark on top of
    the robot gives a large but finite Jacobian rather than a division by zero.
    """
    Hx = np.empty((2, 3))
    Hm = np.empty((2, 2))
    z = np.empty(2)
    z[0], z[1] = range_bearing_into(pose, landmark, min_range, Hx, Hm)
    return z, Hx, Hm


@njit(cache=True)
def range_bearing_into(
    pose: np.ndarray, landmark: np.ndarray, min_range: float, Hx: np.ndarray, Hm: np.ndarray
):
    """``range_bearing`` writing the Jacobians into ``Hx`` (2, 3) and ``Hm`` (2, 2) and returning (range,
    bearing): the filter's correction calls it for every reading, and three small arrays a reading cost more
    than the arithmetic."""
    dx = landmark[0] - pose[0]
    dy = landmark[1] - pose[1]
    q = dx * dx + dy * dy
    r = math.sqrt(q)
    bearing = wrap_angle(math.atan2(dy, dx) - pose[2])
    rj = max(r, min_range)
    qj = rj * rj
    Hm[0, 0] = dx / rj
    Hm[0, 1] = dy / rj
    Hm[1, 0] = -dy / qj
    Hm[1, 1] = dx / qj
    Hx[0, 0] = -Hm[0, 0]
    Hx[0, 1] = -Hm[0, 1]
    Hx[0, 2] = 0.0
    Hx[1, 0] = -Hm[1, 0]
    Hx[1, 1] = -Hm[1, 1]
    Hx[1, 2] = -1.0
    return r, bearing


@njit(cache=True)
def inverse_range_bearing(pose: np.ndarray, reading: np.ndarray):
    """Landmark position implied by a reading, and its Jacobians (the inverse sensor model).

    Returns l = (x + r cos(phi + theta), y + r sin(phi + theta)) (2,), Gr = dl/d pose (2, 3) and
    Gz = dl/d (r, phi) (2, 2); det Gz = r.
    """
    r = reading[0]
    heading = reading[1] + pose[2]
    c = math.cos(heading)
    s = math.sin(heading)
    landmark = np.empty(2)
    landmark[0] = pose[0] + r * c
    landmark[1] = pose[1] + r * s
    Gr = np.zeros((2, 3))
    Gr[0, 0] = 1.0
    Gr[1, 1] = 1.0
    Gr[0, 2] = -r * s
    Gr[1, 2] = r * c
    Gz = np.empty((2, 2))
    Gz[0, 0] = c
    Gz[0, 1] = -r * s
    Gz[1, 0] = s
    Gz[1, 1] = r * c
    return landmark, Gr, Gz
