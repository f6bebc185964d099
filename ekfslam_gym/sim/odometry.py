"""Odometry: the robot's true motion over one control step, expressed in a motion model, plus Gaussian noise.

The true motion is the body's pose before and after the step, read from the physics. It is decomposed
*exactly* (no small-angle or arc assumption) so that the only error a filter sees is the noise drawn here, and
that noise is drawn with exactly the covariance reported beside it: a filter that predicts with the measured
control and V M V^T is then consistent. (A prototype that read a chord and a heading change off the body but
predicted with an arc model was over-confident by a factor 2-3.)

Poses are (x m, y m, theta rad). The heading ``theta`` given here may be unwrapped (pymunk's continuous body
angle); the heading change is taken as the plain difference so a turn is never aliased by wrapping.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from .geometry import wrap_angle

HALF_PI = 0.5 * math.pi


def _freeze_noise_vector(params: object, names: tuple[str, ...]) -> None:
    """Validate an alpha-model parameter set (four alphas, then two floors) and attach ``vector``, the (6,)
    read-only array of the parameters in the order the kernels read them."""
    kind = type(params).__name__
    for name in names:
        value = getattr(params, name)
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{kind}.{name} must be finite and >= 0, got {value!r}")
    if getattr(params, names[4]) <= 0.0 or getattr(params, names[5]) <= 0.0:
        raise ValueError(f"{kind} floors must be > 0 so the motion covariance is positive definite")
    vector = np.array([getattr(params, name) for name in names], dtype=np.float64)
    vector.flags.writeable = False
    object.__setattr__(params, "vector", vector)


@dataclass(frozen=True)
class OdometryNoise:
    """Noise of the odometry model (Thrun's alpha model, in standard deviations, plus a floor).

    sigma_rot1  = alpha1 |rot1| + alpha2 |trans| + rot_floor
    sigma_trans = alpha3 |trans| + alpha4 (|rot1| + |rot2|) + trans_floor
    sigma_rot2  = alpha1 |rot2| + alpha2 |trans| + rot_floor

    Units: alpha1 rad/rad, alpha2 rad/m, alpha3 m/m, alpha4 m/rad, floors rad and m. The floors keep the
    motion covariance positive definite when the robot stands still.
    """

    alpha1: float = 0.05
    alpha2: float = 0.02
    alpha3: float = 0.05
    alpha4: float = 0.01
    rot_floor: float = 1e-3
    trans_floor: float = 1e-3

    def __post_init__(self) -> None:
        _freeze_noise_vector(self, ("alpha1", "alpha2", "alpha3", "alpha4", "rot_floor", "trans_floor"))


@dataclass(frozen=True)
class VelocityNoise:
    """Noise of the velocity form (v, omega), in standard deviations, plus a floor.

    sigma_v     = alpha1 |v| + alpha2 |omega| + v_floor
    sigma_omega = alpha3 |v| + alpha4 |omega| + omega_floor

    Units: alpha1 1, alpha2 m/rad, alpha3 rad/m, alpha4 1, v_floor m/s, omega_floor rad/s.
    """

    alpha1: float = 0.05
    alpha2: float = 0.01
    alpha3: float = 0.02
    alpha4: float = 0.05
    v_floor: float = 0.01
    omega_floor: float = 0.01

    def __post_init__(self) -> None:
        _freeze_noise_vector(self, ("alpha1", "alpha2", "alpha3", "alpha4", "v_floor", "omega_floor"))


class OdometryReading(NamedTuple):
    """One step's odometry in the (rot1, trans, rot2) model.

    u: measured (rot1 rad, trans m, rot2 rad), shape (3,); cov: the covariance M (3, 3) of u - u_true;
    u_true: the exact decomposition of the true motion (for tests and diagnostics, not for the filter).
    """

    u: np.ndarray
    cov: np.ndarray
    u_true: np.ndarray


class VelocityReading(NamedTuple):
    """One step's odometry in the velocity model: u = (v m/s, omega rad/s), cov (2, 2), u_true (2,)."""

    u: np.ndarray
    cov: np.ndarray
    u_true: np.ndarray


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


def compose_odometry(pose: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Apply (rot1, trans, rot2) to pose (3,); the heading is not wrapped. Inverse of ``decompose_odometry``."""
    heading = pose[2] + u[0]
    return np.array(
        [pose[0] + u[1] * math.cos(heading), pose[1] + u[1] * math.sin(heading), pose[2] + u[0] + u[2]]
    )


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
def _odometry_reading(
    x0: float,
    y0: float,
    theta0: float,
    x1: float,
    y1: float,
    theta1: float,
    alphas: np.ndarray,
    normals: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, M, u_true): the exact decomposition plus std * normals, and M = diag(std^2)."""
    u_true = np.empty(3)
    u_true[0], u_true[1], u_true[2] = decompose_odometry(x0, y0, theta0, x1, y1, theta1)
    std = odometry_std(u_true[0], u_true[1], u_true[2], alphas)
    u = np.empty(3)
    cov = np.zeros((3, 3))
    for i in range(3):
        u[i] = u_true[i] + std[i] * normals[i]
        cov[i, i] = std[i] * std[i]
    return u, cov, u_true


def measure_odometry(
    pose0: tuple[float, float, float],
    pose1: tuple[float, float, float],
    noise: OdometryNoise,
    rng: np.random.Generator,
) -> OdometryReading:
    """Noisy (rot1, trans, rot2) of the true motion pose0 -> pose1, with its covariance M = diag(std^2).

    The noise is independent per component, std * N(0, 1) (3 normals from ``rng``) with the std reported in
    M, so M is exact.
    """
    u, cov, u_true = _odometry_reading(*pose0, *pose1, noise.vector, rng.standard_normal(3))
    return OdometryReading(u, cov, u_true)


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
def _velocity_reading(
    x0: float,
    y0: float,
    theta0: float,
    x1: float,
    y1: float,
    theta1: float,
    dt: float,
    alphas: np.ndarray,
    normals: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, N, u_true) for the velocity form: the arc's (v, omega) plus std * normals, N = diag(std^2)."""
    u_true = np.empty(2)
    u_true[0], u_true[1] = velocity_from_motion(x0, y0, theta0, x1, y1, theta1, dt)
    a_v = abs(u_true[0])
    a_w = abs(u_true[1])
    std = (alphas[0] * a_v + alphas[1] * a_w + alphas[4], alphas[2] * a_v + alphas[3] * a_w + alphas[5])
    u = np.empty(2)
    cov = np.zeros((2, 2))
    for i in range(2):
        u[i] = u_true[i] + std[i] * normals[i]
        cov[i, i] = std[i] * std[i]
    return u, cov, u_true


def measure_velocity(
    pose0: tuple[float, float, float],
    pose1: tuple[float, float, float],
    dt: float,
    noise: VelocityNoise,
    rng: np.random.Generator,
) -> VelocityReading:
    """Noisy (v, omega) of the motion pose0 -> pose1 over dt seconds, with its covariance diag(std^2)
    (2 normals from ``rng``)."""
    u, cov, u_true = _velocity_reading(*pose0, *pose1, dt, noise.vector, rng.standard_normal(2))
    return VelocityReading(u, cov, u_true)
