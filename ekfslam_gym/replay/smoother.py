"""The full-SLAM smoother beside the filter on the same real data, and the one comparison of the two.

``compare_with_smoother`` smooths what a replay read (a GTSAM 2-D file's own graph, or an MRCLAM drive's
keyframes) and measures the filter's trajectory against the smoother's: the trajectory gap (rms and largest
distance at the smoother's poses), with the smoother's chi^2 and, for a surveyed drive, its landmark errors.

For a drive (``mrclam.Drive``) the graph keeps one pose per time readings were taken (a keyframe) and the
start: the odometry between two keyframes becomes one pose-pose factor, its relative pose composed through the
same velocity-model steps the filter predicts with and its covariance propagated through their Jacobians
(G Sigma G^T + V M V^T, M the filter's step noise); every known-association reading is a range-bearing factor. A prior pins the first pose at
the origin, where the filter starts. Levenberg-Marquardt (``graph.optimizer``) minimises chi^2 = sum e^T Omega e.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..data.gtsam2d import Gtsam2dDataset
from ..filter.models import velocity_motion
from ..graph.factors import landmark_from_range_bearing
from ..graph.optimizer import GTSAM_LM, FactorGraph, OptimizationResult, Values, optimize
from ..graph.smoother import ODOMETRY_JITTER
from .chain import anchored_at_first_pose
from .mrclam import Drive, ReplaySettings, landmark_errors
from .result import Replay

__all__ = [
    "DriveSmoothing",
    "SmootherComparison",
    "compare_with_smoother",
    "keyframe_odometry",
    "smooth_keyframes",
    "trajectory_gap",
]


@dataclass(eq=False)  # holds arrays
class DriveSmoothing:
    """keyframes (P,): the drive steps whose end each pose is (-1 for the start). poses (P, 3), landmarks
    (n, 2) by the slots of ``landmark_ids`` (NaN where never read). dof: residual dimensions minus variable
    dimensions, the chi^2's expected value under the noise model."""

    keyframes: np.ndarray
    poses: np.ndarray
    landmarks: np.ndarray
    result: OptimizationResult
    dof: int

    @property
    def chi2(self) -> float:
        return float(self.result.final_error)


def keyframe_odometry(drive: Drive, keyframes: np.ndarray, settings: ReplaySettings):
    """Relative poses (P-1, 3) between consecutive keyframes and their covariances (P-1, 3, 3), in the frame
    of the earlier keyframe, composed from the drive's steps as the filter predicts them."""
    variances = settings.odometry.variances(drive.increments, drive.dt)
    ends = np.asarray(keyframes) + 1  # pose after step k is drive pose k + 1; the start is 0
    relative = np.zeros((len(ends) - 1, 3))
    covariance = np.zeros((len(ends) - 1, 3, 3))
    M = np.zeros((2, 2))
    for edge in range(len(ends) - 1):
        pose = np.zeros(3)
        sigma = np.zeros((3, 3))
        for k in range(ends[edge], ends[edge + 1]):
            new_pose, G, V = velocity_motion(pose, drive.increments[k, 0], drive.increments[k, 1], 1.0)
            M[0, 0], M[1, 1] = variances[k]
            sigma = G @ sigma @ G.T + V @ M @ V.T
            pose = new_pose
        relative[edge] = pose
        covariance[edge] = sigma
    return relative, covariance


def smooth_keyframes(
    drive: Drive,
    landmark_ids: np.ndarray,
    settings: ReplaySettings,
    initial_poses: np.ndarray | None = None,
    **options: object,
) -> DriveSmoothing:
    """Smooth ``drive`` with known association; ``initial_poses`` (K+1, 3) (e.g. the filter's path) start
    the keyframes, else dead reckoning does. ``options`` go to ``optimize(..., "lm")``."""
    landmark_ids = np.asarray(landmark_ids, dtype=np.int64)
    slot_of = np.full(int(max(landmark_ids.max(initial=0), drive.subject.max(initial=0))) + 1, -1, np.int64)
    slot_of[landmark_ids] = np.arange(len(landmark_ids))
    counts = np.diff(drive.offsets)
    step_of_reading = np.repeat(np.arange(len(drive)), counts)
    slot = slot_of[drive.subject]
    keep = slot >= 0
    step_of_reading, slot, z = step_of_reading[keep], slot[keep], drive.z[keep]
    keyframes = np.concatenate([[-1], np.unique(step_of_reading)])
    relative, covariance = keyframe_odometry(drive, keyframes, settings)

    # the between error's translation is in the measured relative pose's frame: rotate its covariance there
    c, s = np.cos(relative[:, 2]), np.sin(relative[:, 2])
    Rz = np.zeros((len(relative), 3, 3))
    Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = c, s, -s, c, 1.0
    edge_cov = Rz @ covariance @ np.swapaxes(Rz, 1, 2) + ODOMETRY_JITTER * np.eye(3)

    if initial_poses is None:
        poses0 = np.zeros((len(keyframes), 3))
        for edge, step in enumerate(relative):
            x, y, theta = poses0[edge]
            ct, st = np.cos(theta), np.sin(theta)
            poses0[edge + 1] = (
                x + ct * step[0] - st * step[1],
                y + st * step[0] + ct * step[1],
                theta + step[2],
            )
    else:
        poses0 = np.asarray(initial_poses, dtype=float)[keyframes + 1].copy()
    pose_index = np.searchsorted(keyframes, step_of_reading)
    seen, first, variable = np.unique(slot, return_index=True, return_inverse=True)
    landmarks0 = landmark_from_range_bearing(poses0[pose_index[first]].T, z[first].T).T

    graph = FactorGraph()
    graph.add_prior(0, np.zeros(3), 1e10 * np.eye(3))
    graph.add_between(
        np.arange(len(relative)), np.arange(1, len(relative) + 1), relative, np.linalg.inv(edge_cov)
    )
    Q = np.diag([settings.range_std**2, settings.bearing_std**2])
    graph.add_range_bearing(pose_index, variable, z, np.linalg.inv(Q))
    result = optimize(graph, Values(poses0, landmarks0), "lm", **options)
    landmarks = np.full((len(landmark_ids), 2), np.nan)
    landmarks[seen] = result.values.landmarks
    dof = 3 + 3 * len(relative) + 2 * len(z) - 3 * len(keyframes) - 2 * len(seen)
    return DriveSmoothing(keyframes, result.values.poses, landmarks, result, dof)


def trajectory_gap(filter_poses: np.ndarray, smoothed_poses: np.ndarray) -> tuple[float, float]:
    """(rms, largest) distance [m] between two trajectories (n, >= 2) pose by pose."""
    gap = np.hypot(*(np.asarray(smoothed_poses)[:, :2] - np.asarray(filter_poses)[:, :2]).T)
    return float(np.sqrt(np.mean(gap**2))), float(gap.max())


@dataclass(eq=False)  # holds arrays
class SmootherComparison:
    """The smoother run on a replay's data, and how far the filter's trajectory lies from its.

    result: the optimiser's. poses (P, 3): the smoother's trajectory in the filter's frame. gap_rms, gap_max
    [m]: ``trajectory_gap`` at those poses. dof: the chi^2's expected value (None where unknown).
    landmark_errors [m]: the smoother's landmarks after alignment to a survey (None without one)."""

    result: OptimizationResult
    poses: np.ndarray
    gap_rms: float
    gap_max: float
    dof: int | None = None
    landmark_errors: dict[int, float] | None = None

    def figures(self) -> dict[str, Any]:
        """The JSON-ready figures (``chi2``, ``iterations``, ``seconds``, ``trajectory_gap_rms`` / ``_max``;
        ``dof`` and the landmark errors with their median where known)."""
        out: dict[str, Any] = {
            "chi2": float(self.result.final_error),
            "iterations": self.result.iterations,
            "seconds": self.result.seconds,
            "trajectory_gap_rms": self.gap_rms,
            "trajectory_gap_max": self.gap_max,
        }
        if self.dof is not None:
            out["dof"] = self.dof
        if self.landmark_errors is not None:
            out["landmark_errors"] = {str(k): v for k, v in sorted(self.landmark_errors.items())}
            out["median_error"] = float(np.median(list(self.landmark_errors.values())))
        return out


def compare_with_smoother(
    replay: Replay,
    data: Gtsam2dDataset | Drive,
    *,
    settings: ReplaySettings | None = None,
    survey: tuple[np.ndarray, np.ndarray] | None = None,
) -> SmootherComparison:
    """Smooth the data ``replay`` was run on and compare: a GTSAM 2-D file's graph by Levenberg-Marquardt as
    GTSAM runs it, its free gauge fixed at the first pose (the filter's start); or an MRCLAM ``Drive``'s
    keyframes (``smooth_keyframes``, needs the replay's ``settings``; ``survey`` (ids, xy) also scores its
    landmarks after alignment)."""
    if isinstance(data, Gtsam2dDataset):
        problem = data.to_problem()
        result = optimize(problem.graph, problem.initial, "lm", **GTSAM_LM)
        poses = anchored_at_first_pose(result.values.poses).poses(result.values.poses)
        return SmootherComparison(result, poses, *trajectory_gap(replay.poses, poses))
    if settings is None:
        raise ValueError("smoothing a drive needs the replay's settings (its noise)")
    ids = survey[0] if survey is not None else replay.labels[replay.labels > 0]
    smoothing = smooth_keyframes(data, ids, settings, replay.poses)
    errors = None
    if survey is not None:
        estimates = {int(i): xy for i, xy in zip(ids, smoothing.landmarks) if np.all(np.isfinite(xy))}
        errors, _ = landmark_errors(estimates, *survey)
    gap = trajectory_gap(replay.poses[smoothing.keyframes + 1], smoothing.poses)
    return SmootherComparison(smoothing.result, smoothing.poses, *gap, smoothing.dof, errors)
