"""Seeded synthetic drives with known truth, for testing and benchmarking the smoother and graph solver.

A robot steers towards random waypoints in a square arena at constant step length; odometry (r1, t, r2) is the
true motion plus Gaussian control noise M; readings are range and bearing of every landmark within range, plus
Gaussian noise Q. All randomness comes from the `seed` argument.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..graph.factors import range_bearing
from ..graph.se2 import wrap_angle

__all__ = ["SyntheticDrive", "synthetic_drive"]

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)  # holds arrays
class SyntheticDrive:
    """Truth and measurements of a drive; `readings[t]` (k, 3) rows (landmark id, r, φ) are taken at pose t+1."""

    true_poses: Array  # (T+1, 3)
    landmarks: Array  # (N, 2)
    odometry: Array  # (T, 3) noisy (r1, t, r2)
    odometry_cov: Array  # (3, 3) M
    readings: list[Array]
    reading_cov: Array  # (2, 2) Q


def synthetic_drive(
    num_steps: int = 200,
    num_landmarks: int = 20,
    *,
    seed: int = 0,
    arena: float = 20.0,
    step_length: float = 0.5,
    max_turn: float = 0.3,
    max_range: float = 6.0,
    odometry_std: tuple[float, float, float] = (0.01, 0.02, 0.01),
    reading_std: tuple[float, float] = (0.05, 0.02),
) -> SyntheticDrive:
    """Generate a drive of `num_steps` steps among `num_landmarks` landmarks in an `arena`×`arena` m square.

    `max_turn` [rad] bounds the heading change per step; `odometry_std` is (σ_r1, σ_t, σ_r2) [rad, m, rad] and
    `reading_std` (σ_r, σ_φ) [m, rad].
    """
    rng = np.random.default_rng(seed)
    landmarks = rng.uniform(0.0, arena, size=(num_landmarks, 2))
    poses = np.empty((num_steps + 1, 3))
    poses[0] = (arena / 2, arena / 2, rng.uniform(-np.pi, np.pi))
    target = rng.uniform(0.1 * arena, 0.9 * arena, size=2)
    for t in range(num_steps):
        x, y, th = poses[t]
        if np.hypot(*(target - (x, y))) < 2 * step_length:
            target = rng.uniform(0.1 * arena, 0.9 * arena, size=2)
        turn = np.clip(wrap_angle(np.arctan2(target[1] - y, target[0] - x) - th), -max_turn, max_turn)
        r1 = 0.5 * turn
        heading = th + r1
        poses[t + 1] = (
            x + step_length * np.cos(heading),
            y + step_length * np.sin(heading),
            wrap_angle(th + turn),
        )

    dx, dy = np.diff(poses[:, 0]), np.diff(poses[:, 1])
    r1 = wrap_angle(np.arctan2(dy, dx) - poses[:-1, 2])
    true_controls = np.stack([r1, np.hypot(dx, dy), wrap_angle(np.diff(poses[:, 2]) - r1)], axis=1)
    M = np.diag(np.square(odometry_std))
    odometry = true_controls + rng.multivariate_normal(np.zeros(3), M, size=num_steps)

    Q = np.diag(np.square(reading_std))
    readings = []
    for t in range(1, num_steps + 1):
        z = range_bearing(np.repeat(poses[t][:, None], num_landmarks, axis=1), landmarks.T).T
        visible = np.flatnonzero(z[:, 0] < max_range)
        noisy = z[visible] + rng.multivariate_normal(np.zeros(2), Q, size=len(visible))
        noisy[:, 1] = wrap_angle(noisy[:, 1])
        readings.append(np.column_stack([visible.astype(float), noisy]))
    return SyntheticDrive(poses, landmarks, odometry, M, readings, Q)
