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
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .. import compiled


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


@dataclass(frozen=True)
class WheelOdometryNoise:
    """Wheel-encoder odometry: its geometry and noise, in standard deviations (m).

    sigma_left  = wheel_alpha |left| + wheel_floor,  sigma_right = wheel_alpha |right| + wheel_floor
    sigma_slip  = slip_floor + slip_contact * max(|v_previous|, |v_command|) dt, the second term only in a step
                  with wall contact (the commanded speeds of this step and the last, as the body answers a
                  command one substep late)

    wheel_base: m between the wheels (the filter's ``EKFSLAM(wheel_base=...)`` must be the same). The wheels,
    integrated at the physics substep rate, measure the body's travel along its heading and its turn for any
    motion: forward, backward, turning in place, a command changing every step (two arcs in one step, whose
    sideways residual against one arc the reading's slip carries). What they cannot see is the body sliding
    sideways along a wall (docs/filter-and-graph.md, "Known limitations of the filter"); the turn-drive-turn model reads that slide as +-90
    degree turns and its alpha noise as large heading noise, here it is a sideways slip, position only:

    - ``slide_sensed`` (default): the bumper senses the slide (the wall's direction and the wheels' travel), with
      an error of std sigma_slip: the reading is the true motion plus noise drawn with exactly the reported
      covariance, in contact or not, as the odometry model's (consistent by construction);
    - not sensed: the slip is what the wheels' arcs explain and the slide is left out, only reported as the
      variance sigma_slip^2. Not consistent: a slide keeps its direction along a wall for many steps, which
      per-step independent noise does not describe.

    The slip floor only keeps the motion covariance definite. Units: wheel_alpha and slip_contact m/m, floors m.
    """

    wheel_base: float = 0.3
    wheel_alpha: float = 0.01
    wheel_floor: float = 2e-4
    slip_floor: float = 1e-5
    slip_contact: float = 0.35
    slide_sensed: bool = True

    def __post_init__(self) -> None:
        names = ("wheel_alpha", "wheel_floor", "slip_floor", "slip_contact")
        for name in ("wheel_base", *names):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"WheelOdometryNoise.{name} must be finite and >= 0, got {value!r}")
        if self.wheel_base <= 0.0 or self.wheel_floor <= 0.0 or self.slip_floor <= 0.0:
            raise ValueError(
                "WheelOdometryNoise wheel_base and floors must be > 0 so the motion covariance is positive definite"
            )
        if not isinstance(self.slide_sensed, bool):
            raise ValueError(f"WheelOdometryNoise.slide_sensed must be a bool, got {self.slide_sensed!r}")
        vector = np.array(
            [*(getattr(self, name) for name in names), float(self.slide_sensed)], dtype=np.float64
        )
        vector.flags.writeable = False
        object.__setattr__(self, "vector", vector)


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


class WheelOdometryReading(NamedTuple):
    """One step's wheel odometry: u = (left m, right m, slip m); cov (3, 3) diagonal; u_true (3,) the exact
    decomposition of the true motion (for tests and diagnostics, not for the filter)."""

    u: np.ndarray
    cov: np.ndarray
    u_true: np.ndarray


def compose_odometry(pose: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Apply (rot1, trans, rot2) to pose (3,); the heading is not wrapped. Inverse of ``decompose_odometry``."""
    heading = pose[2] + u[0]
    return np.array(
        [pose[0] + u[1] * math.cos(heading), pose[1] + u[1] * math.sin(heading), pose[2] + u[0] + u[2]]
    )


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
    reading = OdometryReading(np.empty(3), np.zeros((3, 3)), np.empty(3))
    compiled.odometry_reading(*pose0, *pose1, noise.vector, rng.standard_normal(3), *reading)
    return reading


def measure_velocity(
    pose0: tuple[float, float, float],
    pose1: tuple[float, float, float],
    dt: float,
    noise: VelocityNoise,
    rng: np.random.Generator,
) -> VelocityReading:
    """Noisy (v, omega) of the motion pose0 -> pose1 over dt seconds, with its covariance diag(std^2)
    (2 normals from ``rng``)."""
    reading = VelocityReading(np.empty(2), np.zeros((2, 2)), np.empty(2))
    compiled.velocity_reading(*pose0, *pose1, dt, noise.vector, rng.standard_normal(2), *reading)
    return reading


def measure_wheels(
    trace: Sequence[tuple[float, float, float]],
    noise: WheelOdometryNoise,
    contact_travel: float,
    rng: np.random.Generator,
) -> WheelOdometryReading:
    """Wheel odometry of one step from the true poses after each of its substeps (``trace``, the start pose
    first; the start and end poses suffice when the slide is sensed), with the covariance diag(std^2) (3
    normals from ``rng``). ``contact_travel``: the commanded travel
    (m) of a step in contact with a wall, else 0 (see ``WheelOdometryNoise``)."""
    reading = WheelOdometryReading(np.empty(3), np.zeros((3, 3)), np.empty(3))
    compiled.wheel_reading(
        np.array(trace, dtype=np.float64), noise.wheel_base, float(contact_travel), noise.vector,
        rng.standard_normal(3), *reading,
    )  # fmt: skip
    return reading


def __getattr__(name: str):
    # The compiled helpers, loaded with numba on first use so that importing this module never loads it.
    if name in (
        "decompose_odometry",
        "decompose_wheels",
        "odometry_std",
        "velocity_from_motion",
        "velocity_std",
        "wheel_std",
    ):
        from . import odometry_kernels

        return getattr(odometry_kernels, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
