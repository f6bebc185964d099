"""Seeded drives whose noise is exactly what the filter assumes, for consistency and bookkeeping tests."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ekfslam_gym.filter.models import odometry_motion, range_bearing, wrap_angle


@dataclass
class Drive:
    true_poses: np.ndarray  # (T+1, 3)
    controls: np.ndarray  # (T, 3) measured (rot1, trans, rot2)
    readings: list  # per step: (ids (m,), z (m, 2))
    landmarks: np.ndarray  # (n, 2)


def ring_landmarks(n: int, radii=(2.5, 5.5)) -> np.ndarray:
    """n landmarks around the origin, alternately inside and outside the driven circle."""
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False)
    radius = np.where(np.arange(n) % 2 == 0, radii[0], radii[1])
    return np.column_stack([radius * np.cos(angles), radius * np.sin(angles)])


def loop_drive(
    rng: np.random.Generator,
    steps: int,
    landmarks: np.ndarray,
    control_cov: np.ndarray,
    measurement_cov: np.ndarray,
    max_range: float = 3.0,
    trans: float = 0.2,
    turn: float = 0.05,
) -> Drive:
    """A robot circling the origin (radius about trans/turn) reading landmarks within max_range.

    The true motion uses the nominal control; the filter gets the control plus N(0, control_cov), and the
    readings carry N(0, measurement_cov): the noise the filter models, so its NEES should be chi-square.
    """
    radius = trans / (2 * np.sin(turn / 2))  # one lap takes 2 pi / turn steps
    pose = np.array([0.0, -radius, 0.0])
    chol_m = np.linalg.cholesky(control_cov)
    chol_q = np.linalg.cholesky(measurement_cov)
    poses = [pose.copy()]
    controls, readings = [], []
    nominal = np.array([turn / 2, trans, turn / 2])
    for _ in range(steps):
        pose, _, _ = odometry_motion(pose, *nominal)
        poses.append(pose.copy())
        controls.append(nominal + chol_m @ rng.standard_normal(3))
        ids, zs = [], []
        for j, lm in enumerate(landmarks):
            z, _, _ = range_bearing(pose, lm, 1e-3)
            if z[0] <= max_range:
                noisy = z + chol_q @ rng.standard_normal(2)
                noisy[1] = wrap_angle(noisy[1])
                ids.append(j)
                zs.append(noisy)
        readings.append((np.array(ids, dtype=np.int64), np.array(zs).reshape(-1, 2)))
    return Drive(np.array(poses), np.array(controls), readings, landmarks)
