"""Cooperative SLAM on MRCLAM: the five robots' drives through one joint filter (``filter.team.TeamEKF``).

Every robot's odometry, landmark readings and readings of the other robots go through one centralised EKF in
time order. Each robot's drive is stepped as ``replay.mrclam.build_drive`` steps a single robot's (zero-order
hold of the velocity odometry, the velocity model on the increments with dt = 1 s), with extra step ends at the
times other robots read it, so that a robot-to-robot reading meets both robots' poses at its own time. Steps
that end at one time are predicted first, then their readings are fused: landmark readings by barcode (known
association), robot readings as relative range-bearing measurements.

Starting poses. The filter's frame is robot 1's start (the origin, as the single-robot replay). The other robots'
starts are not in this copy of the data (no pose truth): each is taken from the first ``start_window`` seconds
of its own single-robot replay, whose map (in its own start frame) is laid by the best SE(2) alignment
(``alignment.align_se2``) onto robot 1's map of the same window; the window grows until they share two
landmarks. The filter starts them there with a prior of ``start_std`` (m, m, rad). Landmarks start unseen.

Without pose truth, the filter is judged as the single robot's is: landmark errors after the best SE(2)
alignment of its map onto the survey, and NIS (2 dof) of each re-observation, landmark and robot readings apart.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..data.mrclam import ROBOT_SUBJECTS, MRCLAMRun
from ..evaluation.alignment import SE2Transform, align_se2
from ..filter.settings import VARIANTS
from ..filter.team import TeamEKF
from .mrclam import Drive, IncrementNoise, ReplaySettings, build_drive, landmark_errors, replay_drive

__all__ = [
    "TeamReplay",
    "TeamReplaySettings",
    "replay_team",
    "split_drive",
    "start_poses",
    "team_drives",
]


@dataclass(frozen=True)
class TeamReplaySettings:
    """How the joint filter runs: its ``variant`` (ekf, fej, iekf), the landmark readings' noise
    (``range_std`` m, ``bearing_std`` rad; the textbook EKF's by default), the odometry noise
    (``IncrementNoise``), the landmark prior (m^2), whether robot readings are fused (``robot_readings``) and
    their noise (``robot_range_std`` m, ``robot_bearing_std`` rad; None: the landmark readings'), the window (s)
    of the single-robot replays whose maps place the robots' starts, and the starts' prior standard deviations
    (x m, y m, heading rad). ``seconds`` > 0 replays only the first that many seconds (an excerpt).
    ``with_noise_of(single_robot_settings)`` takes a single-robot replay's noise (e.g. ``FITTED_MRCLAM``)."""

    variant: str = "ekf"
    range_std: float = 0.15
    bearing_std: float = 0.08
    odometry: IncrementNoise = field(default_factory=IncrementNoise)
    landmark_prior: float = 100.0
    robot_readings: bool = True
    robot_range_std: float | None = None
    robot_bearing_std: float | None = None
    start_window: float = 120.0
    start_std: tuple[float, float, float] = (0.3, 0.3, 0.15)
    seconds: float = 0.0

    def __post_init__(self) -> None:
        if self.variant not in VARIANTS:
            raise ValueError(f"TeamReplaySettings.variant must be {'|'.join(VARIANTS)}, got {self.variant!r}")
        for name in ("range_std", "bearing_std", "landmark_prior"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"TeamReplaySettings.{name} must be > 0, got {value!r}")
        for name in ("robot_range_std", "robot_bearing_std"):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value > 0):
                raise ValueError(f"TeamReplaySettings.{name} must be > 0 or None, got {value!r}")
        if not (np.isfinite(self.start_window) and self.start_window > 0):
            raise ValueError(f"TeamReplaySettings.start_window must be > 0 s, got {self.start_window!r}")
        if len(self.start_std) != 3 or not all(np.isfinite(s) and s > 0 for s in self.start_std):
            raise ValueError(
                f"TeamReplaySettings.start_std must be three numbers > 0, got {self.start_std!r}"
            )
        if not (np.isfinite(self.seconds) and self.seconds >= 0):
            raise ValueError(f"TeamReplaySettings.seconds must be >= 0, got {self.seconds!r}")

    @classmethod
    def with_noise_of(cls, single: ReplaySettings, **changes: Any) -> TeamReplaySettings:
        """The reading and odometry noise of a single-robot replay's settings, with ``changes``."""
        noise = {
            "range_std": single.range_std,
            "bearing_std": single.bearing_std,
            "odometry": single.odometry,
        }
        return cls(**{**noise, **changes})

    def single_robot(self) -> ReplaySettings:
        """A single-robot replay with this noise (the start placement's)."""
        return ReplaySettings(range_std=self.range_std, bearing_std=self.bearing_std, odometry=self.odometry)

    def measurement_noise(self) -> np.ndarray:
        """Q of one landmark reading (2, 2)."""
        return np.diag([self.range_std**2, self.bearing_std**2])

    def robot_noise(self) -> np.ndarray:
        """Q of one robot reading (2, 2)."""
        range_std = self.range_std if self.robot_range_std is None else self.robot_range_std
        bearing_std = self.bearing_std if self.robot_bearing_std is None else self.robot_bearing_std
        return np.diag([range_std**2, bearing_std**2])


def split_drive(drive: Drive, times: np.ndarray) -> Drive:
    """``drive`` with extra step ends at ``times`` (s) inside it: a step cut in two shares its increments in
    proportion to the time (the zero-order hold makes that exact); readings stay at their times."""
    times = np.asarray(times, dtype=float)
    inside = times[(times > drive.time[0]) & (times < drive.time[-1])]
    grid = np.union1d(drive.time, inside)
    if len(grid) == len(drive.time):
        return drive
    old = np.searchsorted(drive.time, grid[:-1], side="right") - 1
    fraction = np.diff(grid) / drive.dt[old]
    increments = drive.increments[old] * fraction[:, None]
    reading_step = np.repeat(np.arange(len(drive)), np.diff(drive.offsets))
    new_step = np.searchsorted(grid, drive.time[reading_step + 1]) - 1
    offsets = np.searchsorted(new_step, np.arange(len(grid)), side="left")
    return Drive(grid, increments, offsets, drive.z, drive.subject)


def team_drives(runs: list[MRCLAMRun]) -> list[Drive]:
    """Each robot's drive with its landmark and robot readings, cut at the times the others read it."""
    drives = [build_drive(run, robots=True) for run in runs]
    subjects = [run.robot for run in runs]
    out = []
    for k, drive in enumerate(drives):
        read_at = [
            _reading_times(other)[other.subject == subjects[k]] for j, other in enumerate(drives) if j != k
        ]
        out.append(split_drive(drive, np.concatenate(read_at) if read_at else np.zeros(0)))
    return out


def _reading_times(drive: Drive) -> np.ndarray:
    """The time (s) of each of ``drive``'s readings (M,): the end of its step."""
    return drive.time[1:][np.repeat(np.arange(len(drive)), np.diff(drive.offsets))]


def _head(drive: Drive, seconds: float) -> Drive:
    """The steps of ``drive`` that end within ``seconds`` of its start."""
    steps = int(np.searchsorted(drive.time[1:], drive.time[0] + seconds, side="right"))
    return Drive(
        drive.time[: steps + 1],
        drive.increments[:steps],
        drive.offsets[: steps + 1],
        drive.z[: drive.offsets[steps]],
        drive.subject[: drive.offsets[steps]],
    )


def start_poses(
    runs: list[MRCLAMRun], settings: ReplaySettings, window: float
) -> tuple[np.ndarray, list[float]]:
    """Each robot's start (x, y, heading) in the first robot's start frame, from the maps of single-robot
    replays of their first ``window`` s (grown by half until the two maps share two landmarks), and the window
    used for each."""
    ids = runs[0].landmarks.ids
    drives = [build_drive(run) for run in runs]
    poses = np.zeros((len(runs), 3))
    windows = [window]
    reference_maps: dict[float, dict[int, np.ndarray]] = {}
    for k in range(1, len(runs)):
        span = window
        while True:
            if span not in reference_maps:
                reference_maps[span] = replay_drive(
                    _head(drives[0], span), ids, settings
                ).landmark_estimates()
            reference = reference_maps[span]
            own = replay_drive(_head(drives[k], span), ids, settings).landmark_estimates()
            common = sorted(set(reference) & set(own))
            longest = max(drives[0].time[-1] - drives[0].time[0], drives[k].time[-1] - drives[k].time[0])
            if len(common) >= 2 or span >= longest:
                break
            span *= 1.5
        if len(common) < 2:
            raise ValueError(
                f"robot {runs[k].robot} and robot {runs[0].robot} never map two common landmarks: "
                "no start can be placed"
            )
        transform = align_se2(np.array([own[i] for i in common]), np.array([reference[i] for i in common]))
        poses[k] = [*transform.translation, transform.angle]
        windows.append(span)
    return poses, windows


@dataclass(eq=False)  # holds arrays
class TeamReplay:
    """A joint replay: the filter at the end, each robot's path, the NIS of the readings.

    paths: per robot (K_r + 1, 3), its pose estimate after each of its steps; path_times the matching times.
    landmark_nis (L,), landmark_observer (L,) robot index, landmark_nis_time (L,) s; robot_nis (M,),
    robot_observer (M,), robot_target (M,), robot_nis_time (M,) s: each re-observation's NIS (2 dof) before the
    correction that used it, and its time. seconds: the filter's own time.
    """

    team: TeamEKF
    runs: list[MRCLAMRun]
    drives: list[Drive]
    settings: TeamReplaySettings
    starts: np.ndarray
    paths: list[np.ndarray]
    path_times: list[np.ndarray]
    landmark_nis: np.ndarray
    landmark_observer: np.ndarray
    robot_nis: np.ndarray
    robot_observer: np.ndarray
    robot_target: np.ndarray
    seconds: float
    events: int
    landmark_nis_time: np.ndarray
    robot_nis_time: np.ndarray

    def landmark_estimates(self) -> dict[int, np.ndarray]:
        """``{subject: (x, y)}`` of the landmarks the team mapped."""
        ids = self.runs[0].landmarks.ids
        return {int(i): self.team.landmarks[s].copy() for s, i in enumerate(ids) if self.team.observed[s]}

    def landmark_errors(self) -> tuple[dict[int, float], SE2Transform]:
        """Each mapped landmark's distance (m) to the survey after the best SE(2) alignment, and that
        alignment."""
        landmarks = self.runs[0].landmarks
        return landmark_errors(self.landmark_estimates(), landmarks.ids, landmarks.positions)


def replay_team(runs: list[MRCLAMRun], settings: TeamReplaySettings | None = None) -> TeamReplay:
    """Replay the robots of ``runs`` (one MRCLAM data set, any robots, the first one's start as the origin)
    through one ``TeamEKF``."""
    settings = TeamReplaySettings() if settings is None else settings
    if not runs:
        raise ValueError("replay_team needs at least one robot's run")
    ids = runs[0].landmarks.ids
    for run in runs[1:]:
        if not np.array_equal(run.landmarks.ids, ids):
            raise ValueError(f"robot {run.robot}'s landmarks differ from robot {runs[0].robot}'s")
    starts, _ = start_poses(runs, settings.single_robot(), settings.start_window)
    drives = team_drives(runs)
    if settings.seconds > 0:
        begin = min(d.time[0] for d in drives)
        drives = [_head(d, begin + settings.seconds - d.time[0]) for d in drives]
    n = len(runs)
    start_cov = np.diag(np.square(settings.start_std))
    covs = np.stack([1e-10 * np.eye(3) if k == 0 else start_cov for k in range(n)])  # the first: the origin
    team = TeamEKF(
        n, len(ids), motion_model="velocity", dt=1.0, variant=settings.variant,
        measurement_noise=settings.measurement_noise(), robot_measurement_noise=settings.robot_noise(),
        landmark_prior=settings.landmark_prior, init_mode="inverse", initial_poses=starts, initial_pose_covs=covs,
    )  # fmt: skip
    slot_of = np.full(max(int(ids.max()), max(ROBOT_SUBJECTS)) + 1, -1, np.int64)
    slot_of[ids] = np.arange(len(ids))
    robot_of = np.full(len(slot_of), -1, np.int64)
    for k, run in enumerate(runs):
        robot_of[run.robot] = k

    step_covs = []
    for drive in drives:
        variances = settings.odometry.variances(drive.increments, drive.dt)
        c = np.zeros((len(drive), 2, 2))
        c[:, 0, 0], c[:, 1, 1] = variances[:, 0], variances[:, 1]
        step_covs.append(c)
    # every step of every robot, by its end time; at one time the predictions come before the readings
    end_time = np.concatenate([d.time[1:] for d in drives])
    robot = np.concatenate([np.full(len(d), k) for k, d in enumerate(drives)])
    step = np.concatenate([np.arange(len(d)) for d in drives])
    order = np.lexsort((robot, end_time))
    end_time, robot, step = end_time[order], robot[order], step[order]
    group_ends = np.flatnonzero(np.diff(end_time)) + 1
    groups = np.split(np.arange(len(order)), group_ends)

    paths = [np.empty((len(d) + 1, 3)) for d in drives]
    for k in range(n):
        paths[k][0] = team.pose(k)
    nis = {name: [] for name in ("landmark", "landmark_observer", "landmark_time", "robot", "robot_observer",
                                 "robot_target", "robot_time")}  # fmt: skip
    seconds = 0.0
    for group in groups:
        tic = time.perf_counter()
        for e in group:
            k, s = int(robot[e]), int(step[e])
            team.predict(k, drives[k].increments[s], control_cov=step_covs[k][s])
        seconds += time.perf_counter() - tic
        for e in group:
            k, s = int(robot[e]), int(step[e])
            rows = drives[k].readings(s)
            if rows.stop > rows.start:
                z, subject = drives[k].z[rows], drives[k].subject[rows]
                before = len(nis["landmark"]), len(nis["robot"])
                seconds += _fuse(team, k, z, subject, slot_of, robot_of, settings.robot_readings, nis)
                for kind, count in zip(("landmark", "robot"), before, strict=True):
                    if len(nis[kind]) > count:
                        nis[f"{kind}_time"].append(np.full(len(nis[kind][-1]), end_time[e]))
        for e in group:
            k, s = int(robot[e]), int(step[e])
            paths[k][s + 1] = team.pose(k)
    path_times = [d.time.copy() for d in drives]
    return TeamReplay(
        team, list(runs), drives, settings, starts, paths, path_times,
        _array(nis["landmark"]), _array(nis["landmark_observer"], int), _array(nis["robot"]),
        _array(nis["robot_observer"], int), _array(nis["robot_target"], int), seconds, len(order),
        _array(nis["landmark_time"]), _array(nis["robot_time"]),
    )  # fmt: skip


def _fuse(team, k, z, subject, slot_of, robot_of, robot_readings, nis) -> float:
    """Robot ``k``'s readings at one time: landmarks, then the other robots; their NIS recorded first.
    Returns the filter's time (s)."""
    seconds = 0.0
    slots = slot_of[subject]
    landmark = slots >= 0
    if np.any(landmark):
        slots, zl = slots[landmark], z[landmark]
        seen = team.observed[slots]
        if np.any(seen):
            nis["landmark"].append(team.reading_nis(k, zl[seen], landmarks=slots[seen]))
            nis["landmark_observer"].append(np.full(int(seen.sum()), k))
        tic = time.perf_counter()
        team.correct(k, slots, zl)
        seconds += time.perf_counter() - tic
    targets = robot_of[subject]
    other = (targets >= 0) & (targets != k) & (slot_of[subject] < 0)
    if robot_readings and np.any(other):
        targets, zr = targets[other], z[other]
        nis["robot"].append(team.reading_nis(k, zr, robots=targets))
        nis["robot_observer"].append(np.full(len(targets), k))
        nis["robot_target"].append(targets)
        tic = time.perf_counter()
        team.correct_robots(k, targets, zr)
        seconds += time.perf_counter() - tic
    return seconds


def _array(parts: list, dtype=float) -> np.ndarray:
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)
