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

import time
from dataclasses import dataclass, field

import numpy as np

from ..data.mrclam import MRCLAMRun
from ..envs.association_truth import tally_associations
from ..filter import EKFSLAM
from .alignment import SE2Transform, align_se2
from .innovations import group_innovations

__all__ = [
    "FITTED_MRCLAM",
    "Drive",
    "IncrementNoise",
    "ReplaySettings",
    "RealReplay",
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


@dataclass(frozen=True)
class ReplaySettings:
    """How the filter runs: its variant (``ekf``, ``fej``, ``iekf``), association (``known`` by barcode, or
    ``nearest`` / ``jcbc`` with the barcodes hidden), reading noise (m, rad), odometry noise, landmark
    initialisation and prior (m^2), and for unknown association the gates and the landmark slots to hold.

    The default reading noise is the textbook EKF's, the one it is compared with (range 0.15 m, bearing 0.08 rad);
    ``FITTED_MRCLAM`` holds the noise fitted to MRCLAM robot 1."""

    variant: str = "ekf"
    association: str = "known"
    range_std: float = 0.15
    bearing_std: float = 0.08
    odometry: IncrementNoise = field(default_factory=IncrementNoise)
    init_mode: str = "inverse"
    landmark_prior: float = 100.0
    gate_prob: float = 0.99
    new_gate_prob: float = 0.999
    confirm_steps: int = 5
    slots: int = 60


# The noise of MRCLAM robot 1 fitted by maximum likelihood of the filter's innovations (``calibration.fit_noise``
# on ``build_drive(run, merge=0.25)``, 150 filter runs from ``ReplaySettings()``; docs/real-data.md).
FITTED_MRCLAM = ReplaySettings(
    range_std=0.1112, bearing_std=0.00622, odometry=IncrementNoise(distance=0.1805, turn=0.1566, drift=0.0960)
)


@dataclass(eq=False)  # holds arrays
class RealReplay:
    """A replayed drive: the filter at the end, its path, and the innovation statistics.

    poses (K+1, 3): the estimate after each step. labels (n,): the subject each slot holds (-1: none; with
    known association the landmarks' subjects). nis (R,) and nis_time (R,): each re-observation's NIS (2 dof)
    before its correction and its time. log_likelihood: sum over steps of log N(innovation; 0, S) of the
    re-observations jointly. seconds: the filter's own time (predictions and corrections, nothing else).
    false / missed: associations against the barcodes (unknown association only).
    """

    ekf: EKFSLAM
    drive: Drive
    settings: ReplaySettings
    poses: np.ndarray
    labels: np.ndarray
    nis: np.ndarray
    nis_time: np.ndarray
    log_likelihood: float
    seconds: float
    false: int = 0
    missed: int = 0
    new: int = 0

    def landmark_estimates(self) -> dict[int, np.ndarray]:
        """``{subject: (x, y)}`` of the slots that hold a landmark; with two slots for one subject, the one
        initialised first (lower slot)."""
        out: dict[int, np.ndarray] = {}
        for slot in np.flatnonzero(self.ekf.observed):
            subject = int(self.labels[slot])
            if subject > 0 and subject not in out:
                out[subject] = self.ekf.landmarks[slot].copy()
        return out

    @property
    def steps_per_second(self) -> float:
        return len(self.drive) / self.seconds if self.seconds > 0 else float("inf")


def replay_drive(
    drive: Drive, landmark_ids: np.ndarray, settings: ReplaySettings | None = None
) -> RealReplay:
    """Run EKF-SLAM over ``drive`` from the origin; ``landmark_ids`` (n,) are the landmark subjects, the slots
    of known association (readings of other subjects are then skipped)."""
    settings = ReplaySettings() if settings is None else settings
    known = settings.association == "known"
    landmark_ids = np.asarray(landmark_ids, dtype=np.int64)
    n_slots = len(landmark_ids) if known else settings.slots
    Q = np.diag([settings.range_std**2, settings.bearing_std**2])
    ekf = EKFSLAM(
        n_slots, motion_model="velocity", dt=1.0, variant=settings.variant, measurement_noise=Q,
        landmark_prior=settings.landmark_prior, pose_prior=1e-10, init_mode=settings.init_mode,
        initial_pose=np.zeros(3),
    )  # fmt: skip
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
    nis_values: list[np.ndarray] = []
    nis_times: list[np.ndarray] = []
    log_likelihood = 0.0
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
                if np.any(seen):
                    nis, log_like = group_innovations(
                        ekf.mean, ekf.cov, slots[seen], z[seen], Q, ekf.min_range
                    )
                    nis_values.append(nis)
                    nis_times.append(np.full(len(nis), drive.time[k + 1]))
                    log_likelihood += log_like
                tic = time.perf_counter()
                ekf.correct(slots, z)
                seconds += time.perf_counter() - tic
            else:
                mean, cov = ekf.mean.copy(), ekf.cov.copy()
                tic = time.perf_counter()
                result = ekf.correct_unknown(
                    z, settings.association, settings.gate_prob, settings.new_gate_prob,
                    confirm_within=settings.confirm_steps,
                )  # fmt: skip
                seconds += time.perf_counter() - tic
                matched = (result.slots >= 0) & ~result.new
                if np.any(matched):
                    nis, log_like = group_innovations(
                        mean, cov, result.slots[matched], z[matched], Q, ekf.min_range
                    )
                    nis_values.append(nis)
                    nis_times.append(np.full(len(nis), drive.time[k + 1]))
                    log_likelihood += log_like
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
    return RealReplay(
        ekf, drive, settings, poses, labels,
        np.concatenate(nis_values) if nis_values else np.zeros(0),
        np.concatenate(nis_times) if nis_times else np.zeros(0),
        log_likelihood, seconds, false, missed, new_count,
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
