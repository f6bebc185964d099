"""Judge the online filter by the full-SLAM optimum of the same episode.

An env's ``info`` carries, every step, the odometry with its covariance and the readings (and at reset the
first readings), which is all a graph needs: ``episodes.EpisodeRecorder`` collects them and
``compare_with_smoother`` smooths the episode with ``graph.smoother`` and reports the filter's and the
smoother's ATE and landmark RMSE.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..graph.smoother import smooth_drive
from .metrics import ate, landmark_errors

if TYPE_CHECKING:
    from .episodes import EpisodeRecorder


def compare_with_smoother(recorder: EpisodeRecorder, env, method: str = "gn") -> dict[str, float]:
    """Filter vs smoother on the recorded episode: ATE (m, no alignment, over the steps after reset: at reset both
    start at the true pose) and landmark RMSE of the landmarks each estimated (m). ``env`` is the env the episode
    ran in, still at its last step."""
    env = env.unwrapped
    config = env.config
    if config.filter.motion_model not in ("odometry", "wheels"):
        raise ValueError(
            f"the smoother reads odometry or wheels odometry, not {config.filter.motion_model!r}"
        )
    true_poses = np.array(recorder.true_poses)
    smoothed = smooth_drive(
        true_poses[0], np.array(recorder.odometry), np.array(recorder.odometry_cov), recorder.readings,
        config.sensor.cov, initial_pose_cov=config.filter.pose_prior * np.eye(3),
        num_landmarks=env.filter.n_landmarks, method=method, motion_model=config.filter.motion_model,
        wheel_base=env.filter.wheel_base,
    )  # fmt: skip
    truth = env.true_landmarks
    filter_rmse, _ = landmark_errors(np.asarray(env.filter.landmarks), truth, np.asarray(env.filter.observed))
    smoother_seen = ~np.isnan(smoothed.landmarks[:, 0])
    smoother_rmse, _ = landmark_errors(np.nan_to_num(smoothed.landmarks), truth, smoother_seen)
    return {
        "steps": len(recorder.odometry),
        "filter_ate": ate(np.array(recorder.filter_poses)[1:, :2], true_poses[1:, :2]),
        "smoother_ate": ate(smoothed.poses[1:, :2], true_poses[1:, :2]),
        "filter_landmark_rmse": filter_rmse,
        "smoother_landmark_rmse": smoother_rmse,
        "smoother_iterations": smoothed.result.iterations,
        "smoother_seconds": smoothed.result.seconds,
    }
