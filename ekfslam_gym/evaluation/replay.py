"""A recorded drive replayed through EKF-SLAM, with its state read back by the file's landmark ids.

The course's settings (Freiburg *Robot Mapping*, EKF-SLAM exercise): R = diag(0.1, 0.1, 0.01) on the pose,
Q = 0.01 I per reading, landmark prior 1000, zero pose prior at the origin, course initialisation, batch
update. docs/filter-and-graph.md's "Data" section gives the known answers the tests hold it to. ``export_tum`` writes a
replay's trajectories for the evo tools (``data.tum``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..data.course import CourseData, LandmarkMap
from ..filter import COURSE_MEASUREMENT_NOISE, COURSE_MOTION_NOISE, COURSE_SETTINGS, EKFSLAM
from .plotting import Belief, Frame


@dataclass
class ReplayResult:
    """The filter after a replay, with what is needed to read its state by the file's landmark ids."""

    ekf: EKFSLAM
    steps: int
    labels: np.ndarray  # (n,) file id of each landmark slot
    world: LandmarkMap | None = None
    true_poses: np.ndarray | None = None  # (T+1, 3) when the drive is simulated
    frames: list[Frame] = field(default_factory=list)
    last_readings: np.ndarray | None = None  # (m, 2) readings of the last step, for the picture
    est_path: np.ndarray | None = None  # (steps+1, 3) estimated pose after each step

    def landmark_estimates(self) -> dict[int, np.ndarray]:
        """``{file id: (x, y)}`` of the observed landmarks, by id."""
        observed = self.ekf.observed
        landmarks = self.ekf.landmarks
        return {int(self.labels[i]): landmarks[i].copy() for i in np.flatnonzero(observed)}

    def map_errors(self) -> dict[int, float]:
        """Distance [m] from each observed landmark's estimate to its truth (empty without a world)."""
        if self.world is None:
            return {}
        truth = self.world.as_dict()
        return {
            i: float(np.hypot(*(xy - truth[i]))) for i, xy in self.landmark_estimates().items() if i in truth
        }

    def map_rmse(self) -> float | None:
        """Root mean square landmark error [m] over the observed landmarks with a known truth."""
        errors = list(self.map_errors().values())
        return float(np.sqrt(np.mean(np.square(errors)))) if errors else None

    def frame(self) -> Frame:
        """The final belief as a picture frame."""
        return belief_frame(
            self.ekf, self.labels, self.steps, self.last_readings, self.true_poses, self.est_path
        )


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
) -> ReplayResult:
    """Run the course's EKF-SLAM (``COURSE_SETTINGS``, with the course's noise) over the first ``steps`` steps
    of ``data`` (all by default).

    Each step is one prediction with its odometry, then one correction with its readings. ``frame_every`` > 0
    keeps a picture frame every that many steps (and at the last one) for an animation.
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
    for t, block in enumerate(data.steps[:steps], start=1):
        ekf.predict(block.odometry)
        if len(block.ids):
            ekf.correct(slot_of[block.ids], block.z)
        path[t] = ekf.pose
        if frame_every > 0 and (t % frame_every == 0 or t == steps):
            frames.append(belief_frame(ekf, labels, t, block.z, true_poses, path[: t + 1].copy()))
    return ReplayResult(ekf, steps, labels, world, true_poses, frames, data.steps[steps - 1].z, path)


def summary(result: ReplayResult) -> dict[str, object]:
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


def export_tum(result: ReplayResult, path: str | Path) -> list[Path]:
    """Write the estimated trajectory (the start and the pose after each step, t = 0..steps) to ``path`` as a
    TUM file and, when the true poses are known (a simulated drive; course files have none), the true one to
    :func:`true_path_name`. The course format has no clock, so a step is one second: the timestamp is the step.
    """
    from ..data.tum import write_tum

    timestamps = np.arange(result.steps + 1, dtype=float)
    written = [write_tum(path, timestamps, result.est_path[: result.steps + 1])]
    if result.true_poses is not None:
        written.append(write_tum(true_path_name(path), timestamps, result.true_poses[: result.steps + 1]))
    return written
