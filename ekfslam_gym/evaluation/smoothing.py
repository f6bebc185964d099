"""Judge the online filter by the full-SLAM optimum of the same episode.

An env's ``info`` carries, every step, the odometry with its covariance and the readings (and at reset the
first readings), which is all a graph needs: ``EpisodeRecorder`` collects them and
``compare_with_smoother`` smooths the episode with ``graph.smoother`` and reports the filter's and the
smoother's ATE and landmark RMSE.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..graph.smoother import smooth_drive
from .metrics import ate, landmark_errors

SMOOTHED_MOTION_MODELS: tuple[str, ...] = ("odometry", "wheels")
"""The env's ``filter.motion_model`` values whose odometry the smoother reads."""

SMOOTHER_KEYS: tuple[str, ...] = ("smoother_ate", "smoother_landmark_rmse")
"""With ``smoother``: the same episode smoothed by the graph back end (full SLAM), the filter's judge."""


@dataclass
class EpisodeRecorder:
    """Collects one episode from ``reset`` and ``step`` infos: the smoother's edges, so the motion model must be
    one the smoother reads (``SMOOTHED_MOTION_MODELS``: turn-drive-turn or wheel odometry, not velocity)."""

    true_poses: list = field(default_factory=list)
    filter_poses: list = field(default_factory=list)
    odometry: list = field(default_factory=list)
    odometry_cov: list = field(default_factory=list)
    readings: list = field(default_factory=list)

    def add(self, info: dict[str, Any], *, first: bool = False) -> None:
        """Add the info of ``reset`` (``first=True``: no odometry yet) or of a ``step``."""
        if not first:
            if len(info["odometry"]) != 3:  # velocity odometry is (v, omega)
                raise ValueError(
                    f"the smoother reads {' or '.join(SMOOTHED_MOTION_MODELS)} odometry, not velocity "
                    "(filter.motion_model)"
                )
            self.odometry.append(np.asarray(info["odometry"], dtype=float))
            self.odometry_cov.append(np.asarray(info["odometry_cov"], dtype=float))
        self.true_poses.append(np.asarray(info["true_pose"], dtype=float))
        self.filter_poses.append(np.asarray(info["pose"], dtype=float))
        ids, z = info["readings"]
        self.readings.append(
            np.column_stack([np.asarray(ids, dtype=float), np.asarray(z, dtype=float)]).reshape(-1, 3)
        )


def compare_with_smoother(recorder: EpisodeRecorder, env, method: str = "gn") -> dict[str, float]:
    """Filter vs smoother on the recorded episode: ATE (m, no alignment, over the steps after reset: at reset both
    start at the true pose) and landmark RMSE of the landmarks each estimated (m). ``env`` is the env the episode
    ran in, still at its last step."""
    env = env.unwrapped
    config = env.config
    if config.filter.motion_model not in SMOOTHED_MOTION_MODELS:
        raise ValueError(
            f"the smoother reads {' or '.join(SMOOTHED_MOTION_MODELS)} odometry, not {config.filter.motion_model!r}"
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
