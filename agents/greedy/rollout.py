"""The greedy planner's rollouts: the motion primitives, the filter controls each would produce, and the expected
information of driving one (a copy of the filter rolled forward with the readings expected from its own
estimate), plus the expected information of a discovery."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ekfslam_gym.angles import wrap_angles
from ekfslam_gym.envs.actions import PRIMITIVES
from ekfslam_gym.sim.odometry import odometry_std, velocity_std, wheel_std

from ..navigation.veto import arc_poses

DEFAULT_PRIMITIVES = PRIMITIVES  # the env's own set, so a primitives policy and the planner choose alike


def primitive_controls(
    v: float, omega: float, dt: float, horizon: int, motion_model: str, noise: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The filter controls (horizon, 3 or 2), their covariances and the relative poses (horizon + 1, 3).

    ``v`` (m/s) and ``omega`` (rad/s) held for ``horizon`` steps of ``dt`` s trace an arc; in free space the
    robot tracks the command exactly, so each step's true odometry is (omega dt / 2, chord, omega dt / 2)
    with chord = v dt sinc(omega dt / 2), and its covariance is the simulator's alpha model at that motion.
    ``noise`` is the env's ``OdometryNoise`` (or the world's ``VelocityNoise`` for the velocity model, its
    ``WheelOdometryNoise`` for the wheels model: wheel travels v dt -+ b omega dt / 2 on the base b, no slip
    and no wall contact).
    """
    half = 0.5 * omega * dt
    chord = v * dt * (math.sin(half) / half if abs(half) > 1e-9 else 1.0)
    if motion_model == "odometry":
        std = np.asarray(odometry_std(half, chord, half, noise.vector))
        control = np.array([half, chord, half])
    elif motion_model == "wheels":
        left = v * dt - noise.wheel_base * half
        right = v * dt + noise.wheel_base * half
        std = np.asarray(wheel_std(left, right, 0.0, noise.vector))
        control = np.array([left, right, 0.0])
    else:
        std = np.asarray(velocity_std(v, omega, noise.vector))
        control = np.array([v, omega])
    controls = np.tile(control, (horizon, 1))
    covs = np.tile(np.diag(std**2), (horizon, 1, 1))
    return controls, covs, arc_poses(v, omega, dt, horizon)


def expected_readings(
    pose: np.ndarray,
    landmarks: np.ndarray,
    observed: np.ndarray,
    min_range: float,
    max_range: float,
    fov: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Noise-free readings (ids, z) of the observed landmark *estimates* within range and field of view of
    ``pose``; walls are not known to the planner, so nothing is occluded."""
    ids = np.flatnonzero(observed)
    delta = landmarks[ids] - pose[:2]
    ranges = np.hypot(delta[:, 0], delta[:, 1])
    bearings = wrap_angles(np.arctan2(delta[:, 1], delta[:, 0]) - pose[2])
    visible = (ranges >= min_range) & (ranges <= max_range) & (np.abs(bearings) <= 0.5 * fov)
    return ids[visible], np.column_stack([ranges[visible], bearings[visible]])


def rollout(
    ekf: Any, controls: np.ndarray, control_covs: np.ndarray, min_range: float, max_range: float, fov: float
) -> Any:
    """A copy of ``ekf`` predicted with ``controls`` and corrected with the expected readings at every step
    (``ekf`` is left untouched): the belief at the end of a primitive, which a second primitive continues."""
    sim = ekf.copy()
    observed = np.asarray(sim.observed)
    landmarks = np.asarray(sim.landmarks)  # a view: zero-innovation updates leave the means where they are
    for control, cov in zip(controls, control_covs):
        sim.predict(control, control_cov=cov)
        ids, z = expected_readings(np.asarray(sim.pose), landmarks, observed, min_range, max_range, fov)
        if ids.size:
            sim.correct(ids, z)
    return sim


def rollout_gain(
    ekf: Any, controls: np.ndarray, control_covs: np.ndarray, min_range: float, max_range: float, fov: float
) -> float:
    """Expected drop of log det Sigma (nats) after predicting with ``controls`` and correcting with the
    expected readings at every step, on a copy of ``ekf`` (which is left untouched)."""
    return float(ekf.log_det - rollout(ekf, controls, control_covs, min_range, max_range, fov).log_det)


def discovery_nats(
    landmark_prior: float, measurement_cov: np.ndarray, min_range: float, max_range: float
) -> float:
    """Expected information (nats) of a landmark's first reading under inverse-model initialisation:
    ln(prior^2) - E[ln det(Gz Q Gz^T)] with det(Gz Q Gz^T) = r^2 det Q and r area-uniform over the sensor's
    annulus (the pose's own uncertainty is left out: small next to the reading's)."""
    r = np.linspace(max(min_range, 1e-3), max_range, 2001)
    weights = r / r.sum()
    expected_log_r2 = float(np.sum(weights * 2.0 * np.log(r)))
    return 2.0 * math.log(landmark_prior) - (expected_log_r2 + math.log(np.linalg.det(measurement_cov)))
