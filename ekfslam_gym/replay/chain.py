"""EKF-SLAM over a GTSAM 2-D data set whose odometry is one chain (Victoria Park): ``data.gtsam2d`` read, then
replayed step by step with the odometry motion model and the file's own noise.

Each ODOMETRY edge i -> i+1 gives the relative pose (dx, dy, dtheta) and its covariance in pose i's frame: the
filter predicts with (rot1, trans, rot2) = (atan2(dy, dx), |(dx, dy)|, dtheta - rot1), which composes to exactly
that relative pose, and adds the covariance turned into the world frame by the estimated heading. The readings
taken from pose i+1 (known landmark identities) follow, each with its own (range, bearing) covariance.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..data.gtsam2d import Gtsam2dDataset
from ..evaluation.alignment import SE2Transform
from ..filter import EKFSLAM, FilterSettings
from ..filter.settings import KNOWN_START_POSE_PRIOR
from .innovations import group_innovations
from .result import Replay

__all__ = ["anchored_at_first_pose", "check_chain", "replay_chain"]


def check_chain(dataset: Gtsam2dDataset) -> None:
    """Raise ``ValueError`` naming the file unless its edges are the odometry chain 0 -> 1 -> ... in order,
    the one order a filter can read them in."""
    steps = len(dataset.edge_first)
    if not (
        np.array_equal(dataset.edge_first, np.arange(steps))
        and np.array_equal(dataset.edge_second, np.arange(1, steps + 1))
    ):
        raise ValueError(f"{dataset.path}: the filter needs the odometry chain 0 -> 1 -> ... in order")


def replay_chain(dataset: Gtsam2dDataset, variant: str = "ekf", landmark_prior: float = 1e4) -> Replay:
    """Run EKF-SLAM (``variant``, inverse initialisation) over ``dataset`` from pose 0 at the origin: poses are
    the estimate at each pose index, labels the landmark index + 1, ``nis_at`` the pose each re-observation was
    taken from. Raises ``ValueError`` unless the edges are the odometry chain (``check_chain``)."""
    check_chain(dataset)
    steps = len(dataset.edge_first)
    settings = FilterSettings(
        motion_model="odometry", variant=variant, init_mode="inverse", landmark_prior=landmark_prior,
        pose_prior=KNOWN_START_POSE_PRIOR,
    )  # fmt: skip
    ekf = EKFSLAM(dataset.num_landmarks, settings, initial_pose=np.zeros(3))
    order = np.argsort(dataset.reading_pose, kind="stable")
    starts = np.searchsorted(dataset.reading_pose[order], np.arange(steps + 2))
    poses = np.empty((steps + 1, 3))
    nis_values: list[np.ndarray] = []
    nis_poses: list[int] = []
    seconds = 0.0
    for pose in range(steps + 1):
        tic = time.perf_counter()
        if pose > 0:
            dx, dy, dtheta = dataset.edge_measured[pose - 1]
            rot1 = math.atan2(dy, dx) if dx or dy else 0.0
            c, s = math.cos(ekf.pose[2]), math.sin(ekf.pose[2])
            turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
            ekf.predict(
                (rot1, math.hypot(dx, dy), dtheta - rot1),
                motion_cov=turn @ dataset.edge_covariance[pose - 1] @ turn.T,
            )
        seconds += time.perf_counter() - tic
        for reading in order[starts[pose] : starts[pose + 1]]:
            slot = int(dataset.reading_landmark[reading])
            z = dataset.reading[reading]
            Q = dataset.reading_covariance[reading]
            if ekf.observed[slot]:
                nis, _ = group_innovations(ekf.mean, ekf.cov, np.array([slot]), z[None], Q, ekf.min_range)
                nis_values.append(nis)
                nis_poses.append(pose)
            tic = time.perf_counter()
            ekf.correct([slot], z[None], measurement_cov=Q)
            seconds += time.perf_counter() - tic
        poses[pose] = ekf.pose
    nis = np.concatenate(nis_values) if nis_values else np.zeros(0)
    labels = np.arange(1, dataset.num_landmarks + 1, dtype=np.int64)
    return Replay(ekf, poses, labels, nis, np.array(nis_poses, dtype=np.int64), seconds=seconds)


def anchored_at_first_pose(poses: np.ndarray) -> SE2Transform:
    """The rigid motion that puts ``poses[0]`` at the origin facing x, the filter's start: a smoother whose
    gauge is free (no prior) is compared with the filter after it."""
    x, y, theta = poses[0]
    c, s = math.cos(theta), math.sin(theta)
    return SE2Transform(-float(theta), -np.array([c * x + s * y, -s * x + c * y]))
