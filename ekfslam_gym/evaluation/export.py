"""An episode written for the evo tools: its true and estimated trajectories as TUM files and its map as CSV
(``ekfslam_gym.data.tum``)."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

from ..data.tum import write_landmarks_csv, write_tum


def export_tum(
    directory: str | Path, label: str, seed: int, env: gym.Env, true: np.ndarray, estimated: np.ndarray
) -> list[Path]:
    """Write an episode for the evo tools: ``<label>_<seed>_true.tum`` and ``<label>_<seed>_estimate.tum`` (the
    (T, 3) poses after each step t = 1..T, stamped t * dt s: the ones ``ate`` scores, so evo's APE without
    alignment is that ATE) and ``<label>_<seed>_landmarks.csv`` (the env's final map by slot; ``data.tum``)."""

    u = env.unwrapped
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    stem = directory / f"{label}_{seed}"
    timestamps = np.arange(1, len(true) + 1) * float(u.config.dt)
    ekf = u.filter
    return [
        write_tum(f"{stem}_true.tum", timestamps, true),
        write_tum(f"{stem}_estimate.tum", timestamps, estimated),
        write_landmarks_csv(f"{stem}_landmarks.csv", u.true_landmarks, ekf.landmarks, ekf.observed),
    ]
