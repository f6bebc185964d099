"""EKF-SLAM on a real robot: an MRCLAM drive (``data.mrclam``) replayed through ``EKFSLAM``'s velocity model.

The drive becomes a sequence of steps on one clock: a step ends at every change of the odometry command and at
every time a reading was taken, and carries the increments (arc length s = v dt, turn a = omega dt) of the
command in force (a zero-order hold), then the readings taken at its end. The velocity model depends on (v, omega)
only through (v dt, omega dt), so the filter runs with dt = 1 s on the increments: exact for any step length.
Merging the ~67 Hz records with an unchanged command changes nothing but the count of predictions.

Odometry noise (``IncrementNoise``) grows with the distance and the turn of a step, not with the odometry's rate;
readings have a constant (range, bearing) covariance. Without pose truth the filter's consistency is judged by
NIS, and its map by the landmark errors after the best SE(2) alignment to the survey (``alignment``).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from ..data.mrclam import MRCLAMRun
from ..envs.association_truth import tally_associations
from ..evaluation.alignment import SE2Transform, align_se2
from ..filter import EKFSLAM, AssociationSettings, FilterSettings
from ..filter.settings import KNOWN_START_POSE_PRIOR
from .innovations import group_innovations
from .result import Replay

__all__ = [
    "FITTED_MRCLAM",
    "MRCLAM_FILTER",
    "Drive",
    "IncrementNoise",
    "ReplaySettings",
    "build_drive",
    "landmark_errors",
    "replay_drive",
]


@dataclass(frozen=True)
class IncrementNoise:
    """Noise of one odometry step of dt s that moved s m along its arc and turned a rad, as standard deviations
    per square root of what accumulates (random-walk growth, the same for any odometry rate):

        var(s) = distance^2 |s| + distance_floor^2 dt
        var(a) = turn^2 |a| + drift^2 |s| + turn_floor^2 dt

    Units: distance m/sqrt(m), turn rad/sqrt(rad), drift rad/sqrt(m), floors per sqrt(s).
    """

    distance: float = 0.05
    turn: float = 0.1
    drift: float = 0.05
    distance_floor: float = 1e-3
    turn_floor: float = 1e-3

    def __post_init__(self) -> None:
        for name in ("distance", "turn", "drift", "distance_floor", "turn_floor"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"IncrementNoise.{name} must be finite and >= 0, got {value!r}")
        if self.distance_floor <= 0 or self.turn_floor <= 0:
            raise ValueError("IncrementNoise floors must be > 0 so every step's covariance is definite")

    def variances(self, increments: np.ndarray, dt: np.ndarray) -> np.ndarray:
        """(K, 2) variances of (s, a) for increments (K, 2) over dt (K,) s."""
        s, a = np.abs(increments[:, 0]), np.abs(increments[:, 1])
        return np.column_stack(
            [
                self.distance**2 * s + self.distance_floor**2 * dt,
                self.turn**2 * a + self.drift**2 * s + self.turn_floor**2 * dt,
            ]
        )


@dataclass(frozen=True, eq=False)  # holds arrays
class Drive:
    """The steps of a drive on one clock.

    time (K+1,): s, the start then the end of each step. increments (K, 2): arc length s m, turn a rad.
    offsets (K+1,): the readings taken at the end of step k are rows offsets[k]:offsets[k+1] of ``z`` (M, 2)
    (range m, bearing rad) and ``subject`` (M,) (the barcode's subject: the truth, hidden from unknown
    association; 0 for an unknown barcode).
    """

    time: np.ndarray
    increments: np.ndarray
    offsets: np.ndarray
    z: np.ndarray
    subject: np.ndarray

    def __len__(self) -> int:
        return len(self.increments)

    @property
    def dt(self) -> np.ndarray:
        return np.diff(self.time)

    def readings(self, k: int) -> slice:
        return slice(int(self.offsets[k]), int(self.offsets[k + 1]))


def build_drive(run: MRCLAMRun, *, robots: bool = False, merge: float = 0.0) -> Drive:
    """The drive of ``run``: its landmark readings, and with ``robots`` the readings of the other robots too
    (moving barcodes, which a filter that does not know the barcodes must tell from landmarks).

    ``merge`` > 0 s joins consecutive steps into one as long as they span at most ``merge`` s and no reading
    falls inside: their increments add up, so the arcs of several commands become one (an approximation of
    second order in the turn, for a cheaper replay: the noise fit's many runs). 0 keeps every step, exact."""
    odometry = run.odometry
    keep = run.is_landmark_reading() | (robots & (run.subjects() > 0))
    readings = run.measurements.select(keep)
    subject = run.subjects()[keep]
    if not len(odometry):
        raise ValueError("the drive has no odometry")
    command = np.column_stack([odometry.v, odometry.omega])
    changes = np.ones(len(odometry), dtype=bool)
    changes[1:] = np.any(command[1:] != command[:-1], axis=1)
    start = min(odometry.time[0], readings.time[0]) if len(readings) else odometry.time[0]
    reading_times = np.unique(readings.time)
    breaks = np.unique(np.concatenate([[start], odometry.time[changes], reading_times]))
    # the command in force over [breaks[k], breaks[k+1]): the last record at or before breaks[k] (zero before)
    record = np.searchsorted(odometry.time, breaks[:-1], side="right") - 1
    held = np.where(record[:, None] >= 0, command[np.maximum(record, 0)], 0.0)
    increments = held * np.diff(breaks)[:, None]
    # readings at breaks[k+1] belong to step k (none are at the start, which no step ends)
    step_of_reading = np.searchsorted(breaks, readings.time) - 1
    if np.any(step_of_reading < 0):
        raise ValueError("a reading precedes the drive's start")
    offsets = np.searchsorted(step_of_reading, np.arange(len(breaks)), side="left")
    drive = Drive(breaks, increments, offsets, readings.z.copy(), subject.astype(np.int64))
    return _merged(drive, merge) if merge > 0 else drive


def _merged(drive: Drive, span: float) -> Drive:
    """``drive`` with runs of steps joined (see ``build_drive``'s ``merge``)."""
    counts = np.diff(drive.offsets)
    ends = [0]
    start_time = drive.time[0]
    for k in range(len(drive)):
        last = k == len(drive) - 1
        if counts[k] or last or drive.time[k + 2] - start_time > span:
            ends.append(k + 1)
            start_time = drive.time[k + 1]
    ends = np.array(ends)
    increments = np.add.reduceat(drive.increments, ends[:-1], axis=0)
    return Drive(drive.time[ends], increments, drive.offsets[ends], drive.z, drive.subject)


# The filter of a real drive: the velocity model on the drive's increments (run with dt = 1 s, see the module
# docstring), inverse initialisation, landmarks at the env's prior, the start known (the drive's frame is its own).
MRCLAM_FILTER = FilterSettings(
    motion_model="velocity", init_mode="inverse", pose_prior=KNOWN_START_POSE_PRIOR
)


@dataclass(frozen=True)
class ReplaySettings:
    """How a real drive is replayed: the filter (``FilterSettings``: its variant, initialisation and priors;
    the velocity model), the association (``AssociationSettings``: ``known`` by barcode, or ``nearest`` /
    ``jcbc`` with the barcodes hidden, their gates), the reading noise (m, rad), the odometry noise, and the
    landmark slots an unknown association holds.

    The default reading noise is the textbook EKF's, the one it is compared with (range 0.15 m, bearing 0.08 rad);
    ``FITTED_MRCLAM`` holds the noise fitted to MRCLAM robot 1."""

    filter: FilterSettings = MRCLAM_FILTER
    association: AssociationSettings = AssociationSettings()
    range_std: float = 0.15
    bearing_std: float = 0.08
    odometry: IncrementNoise = field(default_factory=IncrementNoise)
    slots: int = 60

    def __post_init__(self) -> None:
        if self.filter.motion_model != "velocity":
            raise ValueError(
                f"a real drive replays through the velocity model, got {self.filter.motion_model!r}"
            )
        for name in ("range_std", "bearing_std"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"ReplaySettings.{name} must be > 0, got {value!r}")
        if isinstance(self.slots, bool) or not isinstance(self.slots, (int, np.integer)) or self.slots < 1:
            raise ValueError(f"ReplaySettings.slots must be an integer >= 1, got {self.slots!r}")

    @property
    def measurement_cov(self) -> np.ndarray:
        """The (range, bearing) covariance of every reading."""
        return np.diag([self.range_std**2, self.bearing_std**2])

    def choosing(self, *, variant: str | None = None, association: str | None = None) -> ReplaySettings:
        """These settings with the filter variant and the association kind replaced (None keeps them)."""
        filter_settings = (
            self.filter if variant is None else dataclasses.replace(self.filter, variant=variant)
        )
        kind = (
            self.association
            if association is None
            else dataclasses.replace(self.association, kind=association)
        )
        return dataclasses.replace(self, filter=filter_settings, association=kind)


# The noise of MRCLAM robot 1 fitted by maximum likelihood of the filter's innovations (``calibration.fit_noise``
# on ``build_drive(run, merge=0.25)``, 150 filter runs from ``ReplaySettings()``; docs/real-data.md).
FITTED_MRCLAM = ReplaySettings(
    range_std=0.1112, bearing_std=0.00622, odometry=IncrementNoise(distance=0.1805, turn=0.1566, drift=0.0960)
)


class _Innovations:
    """The re-observations' NIS, their times and the joint log-likelihood, gathered step by step."""

    def __init__(self, measurement_cov: np.ndarray, min_range: float) -> None:
        self.Q, self.min_range = measurement_cov, min_range
        self.nis: list[np.ndarray] = []
        self.times: list[np.ndarray] = []
        self.log_likelihood = 0.0

    def add(self, mean: np.ndarray, cov: np.ndarray, slots: np.ndarray, z: np.ndarray, time: float) -> None:
        """The readings ``z`` of the initialised ``slots``, from the state (mean, cov) before their correction."""
        if len(slots):
            nis, log_like = group_innovations(mean, cov, slots, z, self.Q, self.min_range)
            self.nis.append(nis)
            self.times.append(np.full(len(nis), time))
            self.log_likelihood += log_like

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        return (
            np.concatenate(self.nis) if self.nis else np.zeros(0),
            np.concatenate(self.times) if self.times else np.zeros(0),
        )


def replay_drive(drive: Drive, landmark_ids: np.ndarray, settings: ReplaySettings | None = None) -> Replay:
    """Run EKF-SLAM over ``drive`` from the origin; ``landmark_ids`` (n,) are the landmark subjects, the slots
    of known association (readings of other subjects are then skipped). The result's labels are the subject
    each slot holds (-1: none), ``nis_at`` each re-observation's time (s)."""
    settings = ReplaySettings() if settings is None else settings
    known = settings.association.kind == "known"
    landmark_ids = np.asarray(landmark_ids, dtype=np.int64)
    n_slots = len(landmark_ids) if known else settings.slots
    Q = settings.measurement_cov
    ekf = EKFSLAM(n_slots, settings.filter, dt=1.0, measurement_noise=Q, initial_pose=np.zeros(3))
    slot_of = np.full(int(max(landmark_ids.max(initial=0), drive.subject.max(initial=0))) + 1, -1, np.int64)
    slot_of[landmark_ids] = np.arange(len(landmark_ids))
    variances = settings.odometry.variances(drive.increments, drive.dt)
    covs = np.zeros((len(drive), 2, 2))
    covs[:, 0, 0], covs[:, 1, 1] = variances[:, 0], variances[:, 1]

    labels = landmark_ids.copy() if known else np.full(n_slots, -1, dtype=np.int64)
    # unknown association's bookkeeping against the barcodes (tally_associations' arrays, by landmark index:
    # slot_of, -1 for a robot's or an unknown barcode, which counts as clutter)
    slot_truth = np.full(n_slots, -1, dtype=np.int64)
    slot_landmarks = np.zeros((n_slots, 2))
    valid = np.zeros(n_slots, dtype=bool)
    dummy_truth = np.zeros((len(landmark_ids), 2))
    false = missed = new_count = 0

    poses = np.empty((len(drive) + 1, 3))
    poses[0] = ekf.pose
    innovations = _Innovations(Q, ekf.min_range)
    seconds = 0.0
    for k in range(len(drive)):
        tic = time.perf_counter()
        ekf.predict(drive.increments[k], control_cov=covs[k])
        seconds += time.perf_counter() - tic
        rows = drive.readings(k)
        z = drive.z[rows]
        if len(z):
            subject = drive.subject[rows]
            if known:
                slots = slot_of[subject]
                keep = slots >= 0
                slots, z = slots[keep], z[keep]
                seen = ekf.observed[slots]
                innovations.add(ekf.mean, ekf.cov, slots[seen], z[seen], drive.time[k + 1])
                tic = time.perf_counter()
                ekf.correct(slots, z)
                seconds += time.perf_counter() - tic
            else:
                mean, cov = ekf.mean.copy(), ekf.cov.copy()
                tic = time.perf_counter()
                result = ekf.correct_unknown(z, settings.association)
                seconds += time.perf_counter() - tic
                matched = (result.slots >= 0) & ~result.new
                innovations.add(mean, cov, result.slots[matched], z[matched], drive.time[k + 1])
                f, m, _, _ = tally_associations(
                    slot_of[subject], z, result.slots, result.new, result.forgotten, ekf.observed,
                    slot_truth, dummy_truth, slot_landmarks, valid,
                )  # fmt: skip
                false += int(f)
                missed += int(m)
                new_count += int(np.sum(result.new))
        poses[k + 1] = ekf.pose
    if not known:
        labels = np.where(slot_truth >= 0, landmark_ids[np.maximum(slot_truth, 0)], -1)
    nis, nis_time = innovations.arrays()
    return Replay(
        ekf, poses, labels, nis, nis_time, innovations.log_likelihood, seconds, false, missed, new_count,
    )  # fmt: skip


def landmark_errors(
    estimates: dict[int, np.ndarray], truth_ids: np.ndarray, truth_xy: np.ndarray
) -> tuple[dict[int, float], SE2Transform]:
    """Each estimated landmark's distance (m) to its surveyed position after the best SE(2) alignment of all
    estimates onto the survey, and that alignment."""
    truth = {int(i): np.asarray(p, dtype=float) for i, p in zip(truth_ids, truth_xy)}
    common = sorted(set(estimates) & set(truth))
    source = np.array([estimates[i] for i in common])
    target = np.array([truth[i] for i in common])
    transform = align_se2(source, target)
    moved = transform.points(source)
    return {i: float(np.hypot(*(moved[n] - target[n]))) for n, i in enumerate(common)}, transform
