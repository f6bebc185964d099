"""The course's recorded drive (``data.course``) replayed through EKF-SLAM, its state read back by the file's
landmark ids.

The course's settings (Freiburg *Robot Mapping*, EKF-SLAM exercise): R = diag(0.1, 0.1, 0.01) on the pose,
Q = 0.01 I per reading, landmark prior 1000, zero pose prior at the origin, course initialisation, batch
update. docs/filter-and-graph.md's "Data" section gives the known answers the tests hold it to. ``export_tum`` writes a
replay's trajectories for the evo tools (``data.tum``).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from ..data.course import CourseData, LandmarkMap
from ..evaluation.plotting import Belief, Frame
from ..filter import COURSE_MEASUREMENT_NOISE, COURSE_MOTION_NOISE, COURSE_SETTINGS, EKFSLAM
from .result import Replay


def map_errors(result: Replay, world: LandmarkMap | None) -> dict[int, float]:
    """Distance [m] from each observed landmark's estimate to its truth in ``world`` (empty without one); the
    course's frame is the world's, so no alignment."""
    if world is None:
        return {}
    truth = world.as_dict()
    return {
        i: float(np.hypot(*(xy - truth[i]))) for i, xy in result.landmark_estimates().items() if i in truth
    }


def map_rmse(result: Replay, world: LandmarkMap | None) -> float | None:
    """Root mean square landmark error [m] over the observed landmarks with a known truth."""
    errors = list(map_errors(result, world).values())
    return float(np.sqrt(np.mean(np.square(errors)))) if errors else None


def final_frame(result: Replay) -> Frame:
    """The final belief as a picture frame."""
    return belief_frame(
        result.ekf, result.labels, result.steps, result.extras.get("last_readings"),
        result.extras.get("true_poses"), result.poses,
    )  # fmt: skip


def landmark_labels(data: CourseData, world: LandmarkMap | None) -> np.ndarray:
    """File id of each landmark slot: the sorted world ids, or 1..max id seen without a world.

    Raises ``ValueError`` naming any id the readings use that the world does not have.
    """
    if world is None:
        return np.arange(1, data.max_id + 1, dtype=np.int64)
    labels = np.sort(world.ids)
    seen = np.unique(np.concatenate([step.ids for step in data.steps] + [np.zeros(0, np.int64)]))
    unknown = np.setdiff1d(seen, labels)
    if len(unknown):
        raise ValueError(f"readings use landmark id(s) {unknown.tolist()} not in the world file")
    return labels


def belief_frame(
    ekf: EKFSLAM,
    labels: np.ndarray,
    step: int,
    readings: np.ndarray | None,
    true_poses: np.ndarray | None,
    est_path: np.ndarray | None,
) -> Frame:
    belief = Belief(
        pose=ekf.pose.copy(),
        pose_cov=ekf.pose_cov.copy(),
        landmarks=ekf.landmarks.copy(),
        landmark_covs=ekf.landmark_covs(),
        observed=ekf.observed.copy(),
        labels=labels,
    )
    return Frame(
        belief,
        step=step,
        readings=readings,
        true_pose=None if true_poses is None else true_poses[step],
        true_path=None if true_poses is None else true_poses[: step + 1],
        est_path=est_path,
    )


def replay(
    data: CourseData,
    *,
    world: LandmarkMap | None = None,
    steps: int | None = None,
    update: str = COURSE_SETTINGS.update,
    init_mode: str = COURSE_SETTINGS.init_mode,
    true_poses: np.ndarray | None = None,
    frame_every: int = 0,
) -> Replay:
    """Run the course's EKF-SLAM (``COURSE_SETTINGS``, with the course's noise) over the first ``steps`` steps
    of ``data`` (all by default).

    Each step is one prediction with its odometry, then one correction with its readings. ``frame_every`` > 0
    keeps a picture frame every that many steps (and at the last one) for an animation (``extras["frames"]``,
    beside the last step's readings and ``true_poses``).
    """
    steps = len(data) if steps is None else steps
    if not 0 < steps <= len(data):
        raise ValueError(f"steps must be in [1, {len(data)}], got {steps}")
    labels = landmark_labels(data, world)
    slot_of = np.full(int(max(labels.max(initial=0), data.max_id)) + 1, -1, dtype=np.int64)
    slot_of[labels] = np.arange(len(labels))

    ekf = EKFSLAM(
        len(labels),
        COURSE_SETTINGS,
        init_mode=init_mode,
        update=update,
        motion_noise=COURSE_MOTION_NOISE,
        measurement_noise=COURSE_MEASUREMENT_NOISE,
        initial_pose=np.zeros(3),
    )
    frames: list[Frame] = []
    path = np.zeros((steps + 1, 3))
    seconds = 0.0
    for t, block in enumerate(data.steps[:steps], start=1):
        tic = time.perf_counter()
        ekf.predict(block.odometry)
        if len(block.ids):
            ekf.correct(slot_of[block.ids], block.z)
        seconds += time.perf_counter() - tic
        path[t] = ekf.pose
        if frame_every > 0 and (t % frame_every == 0 or t == steps):
            frames.append(belief_frame(ekf, labels, t, block.z, true_poses, path[: t + 1].copy()))
    extras = {"frames": frames, "last_readings": data.steps[steps - 1].z, "true_poses": true_poses}
    return Replay(ekf, path, labels, seconds=seconds, extras=extras)


def summary(result: Replay) -> dict[str, object]:
    """The ``--json`` object: steps, pose, pose_cov, observed landmarks by file id, log_det (null if -inf)."""
    log_det = float(result.ekf.log_det)
    return {
        "steps": result.steps,
        "pose": [float(v) for v in result.ekf.pose],
        "pose_cov": [[float(v) for v in row] for row in result.ekf.pose_cov],
        "landmarks": {
            str(i): [float(v) for v in xy] for i, xy in sorted(result.landmark_estimates().items())
        },
        "log_det": log_det if math.isfinite(log_det) else None,
    }


def true_path_name(path: str | Path) -> Path:
    """The file beside an estimate's TUM file that holds the true trajectory: ``<stem>_true<suffix>``."""
    path = Path(path)
    return path.with_name(f"{path.stem}_true{path.suffix}")


def export_tum(result: Replay, path: str | Path) -> list[Path]:
    """Write the estimated trajectory (the start and the pose after each step, t = 0..steps) to ``path`` as a
    TUM file and, when the true poses are known (a simulated drive; course files have none), the true one to
    :func:`true_path_name`. The course format has no clock, so a step is one second: the timestamp is the step.
    """
    from ..data.tum import write_tum

    timestamps = np.arange(result.steps + 1, dtype=float)
    written = [write_tum(path, timestamps, result.poses)]
    true_poses = result.extras.get("true_poses")
    if true_poses is not None:
        written.append(write_tum(true_path_name(path), timestamps, true_poses[: result.steps + 1]))
    return written
