"""Readers for the UTIAS Multi-Robot Cooperative Localization and Mapping data set (MRCLAM).

K. Y. K. Leung, Y. Halpern, T. D. Barfoot and H. H. T. Liu, "The UTIAS multi-robot cooperative localization
and mapping dataset", IJRR 30(8), 2011. Five robots read barcodes on 15 cylindrical landmarks; each data set
folder holds, as whitespace-separated text with ``#`` comment lines:

- ``RobotN_Odometry.dat``: ``time v omega`` (s, m/s, rad/s), the velocity odometry at ~67 Hz;
- ``RobotN_Measurement.dat``: ``time barcode range bearing`` (s, -, m, rad in the robot frame);
- ``Barcodes.dat``: ``subject barcode``; subjects 1-5 are the robots, the rest (6-20) the landmarks;
- ``Landmark_Groundtruth.dat``: ``subject x y std_x std_y`` (m), the landmarks surveyed by Vicon.

A barcode is read on the other robots as well as on the landmarks: those readings are moving objects, not
landmarks, and ``MRCLAMRun.landmark_readings`` leaves them out. Times are Unix seconds on one clock shared by
odometry and measurements. Malformed lines raise ``ValueError`` naming ``file:line`` (``data.records``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .course import LandmarkMap
from .records import Record, read_records

__all__ = [
    "ROBOT_SUBJECTS",
    "MRCLAMRun",
    "Measurements",
    "Odometry",
    "load_mrclam",
    "read_barcodes",
    "read_landmark_truth",
    "read_measurements",
    "read_odometry",
]

PathLike = str | os.PathLike[str]

# Subjects 1-5 carry the robots' barcodes (the data set's README and paper).
ROBOT_SUBJECTS = (1, 2, 3, 4, 5)


@dataclass(frozen=True, eq=False)  # holds arrays
class Odometry:
    """Velocity odometry: ``time`` (n,) s, non-decreasing; ``v`` (n,) m/s forward; ``omega`` (n,) rad/s.

    Each command holds from its time until the next one's (a zero-order hold).
    """

    time: np.ndarray
    v: np.ndarray
    omega: np.ndarray

    def __len__(self) -> int:
        return len(self.time)


@dataclass(frozen=True, eq=False)  # holds arrays
class Measurements:
    """Barcode readings: ``time`` (m,) s, non-decreasing; ``barcode`` (m,) int; ``z`` (m, 2) (range m,
    bearing rad) in the robot frame. Readings taken together share their time."""

    time: np.ndarray
    barcode: np.ndarray
    z: np.ndarray

    def __len__(self) -> int:
        return len(self.time)

    def select(self, mask: np.ndarray) -> Measurements:
        """The readings where ``mask`` (m,) bool is true, in order."""
        return Measurements(self.time[mask], self.barcode[mask], self.z[mask])


@dataclass(frozen=True, eq=False)  # holds arrays
class MRCLAMRun:
    """One robot's drive in one MRCLAM data set, with the barcodes and the surveyed landmarks.

    barcodes: ``{subject: barcode}``. landmarks: the surveyed positions by subject (ids 6-20 in data set 1),
    sorted by subject; landmark_std: (n, 2) the survey's standard deviations (m), same order.
    """

    robot: int
    odometry: Odometry
    measurements: Measurements
    barcodes: dict[int, int]
    landmarks: LandmarkMap
    landmark_std: np.ndarray

    def subjects(self) -> np.ndarray:
        """The subject of every reading (m,), by its barcode; 0 where the barcode is not in ``Barcodes.dat``."""
        lookup = np.zeros(max(self.barcodes.values(), default=0) + 1, dtype=np.int64)
        for subject, barcode in self.barcodes.items():
            lookup[barcode] = subject
        barcode = self.measurements.barcode
        inside = (barcode >= 0) & (barcode < len(lookup))
        return np.where(inside, lookup[np.clip(barcode, 0, len(lookup) - 1)], 0)

    def is_landmark_reading(self) -> np.ndarray:
        """(m,) bool: the readings of surveyed landmarks (not of robots, not of unknown barcodes)."""
        return np.isin(self.subjects(), self.landmarks.ids)

    def landmark_readings(self) -> tuple[Measurements, np.ndarray]:
        """The readings of landmarks only, and the subject (landmark id) of each."""
        keep = self.is_landmark_reading()
        return self.measurements.select(keep), self.subjects()[keep]

    @property
    def duration(self) -> float:
        """Seconds from the first odometry record to the last."""
        return float(self.odometry.time[-1] - self.odometry.time[0]) if len(self.odometry) else 0.0


# --------------------------------------------------------------------------------------------------- parsing


def _rows(path: Path, columns: int, what: str) -> Iterator[Record]:
    """The records of a data file (``#`` starts a comment), each checked to hold ``columns`` values."""
    for record in read_records(path):
        record.expect(columns, what)
        yield record


def _check_time(time: float, previous: float, record: Record) -> None:
    if time < previous:
        raise record.error(f"time {time!r} goes back (previous line {previous!r})")


def read_odometry(path: PathLike) -> Odometry:
    """Read a ``RobotN_Odometry.dat`` file: ``time v omega`` per line, times non-decreasing."""
    rows: list[tuple[float, float, float]] = []
    previous = -math.inf
    for record in _rows(Path(path), 3, "odometry (time v omega)"):
        time = record.number(0, "time")
        _check_time(time, previous, record)
        previous = time
        rows.append((time, record.number(1, "v"), record.number(2, "omega")))
    array = np.array(rows, dtype=float).reshape(-1, 3)
    return Odometry(array[:, 0].copy(), array[:, 1].copy(), array[:, 2].copy())


def read_measurements(path: PathLike) -> Measurements:
    """Read a ``RobotN_Measurement.dat`` file: ``time barcode range bearing`` per line, times non-decreasing,
    ranges positive."""
    times: list[float] = []
    barcodes: list[int] = []
    z: list[tuple[float, float]] = []
    previous = -math.inf
    for record in _rows(Path(path), 4, "measurement (time barcode range bearing)"):
        time = record.number(0, "time")
        _check_time(time, previous, record)
        previous = time
        reading = (record.number(2, "range"), record.number(3, "bearing"))
        if reading[0] <= 0.0:
            raise record.error(f"range {record.tokens[2]!r} is not positive")
        times.append(time)
        barcodes.append(record.integer(1, "barcode", minimum=0))
        z.append(reading)
    return Measurements(
        np.array(times, dtype=float),
        np.array(barcodes, dtype=np.int64),
        np.array(z, dtype=float).reshape(-1, 2),
    )


def read_barcodes(path: PathLike) -> dict[int, int]:
    """Read ``Barcodes.dat``: ``{subject: barcode}``, both distinct."""
    barcodes: dict[int, int] = {}
    line_of: dict[int, str] = {}
    for record in _rows(Path(path), 2, "barcode (subject barcode)"):
        subject = record.integer(0, "subject", minimum=0)
        barcode = record.integer(1, "barcode", minimum=0)
        if subject in barcodes:
            raise record.error(f"subject {subject} already has a barcode ({line_of[subject]})")
        if barcode in barcodes.values():
            raise record.error(f"barcode {barcode} already belongs to another subject")
        barcodes[subject] = barcode
        line_of[subject] = record.where
    return barcodes


def read_landmark_truth(path: PathLike) -> tuple[LandmarkMap, np.ndarray]:
    """Read ``Landmark_Groundtruth.dat``: the landmarks by subject (sorted) and their survey std (n, 2) m."""
    ids: list[int] = []
    rows: list[list[float]] = []
    for record in _rows(Path(path), 5, "landmark (subject x y std_x std_y)"):
        subject = record.integer(0, "subject", minimum=0)
        if subject in ids:
            raise record.error(f"landmark subject {subject} is listed twice")
        values = [record.number(i, name) for i, name in enumerate(("x", "y", "std_x", "std_y"), start=1)]
        if values[2] < 0 or values[3] < 0:
            raise record.error("a standard deviation is negative")
        ids.append(subject)
        rows.append(values)
    table = np.array(rows, dtype=float).reshape(-1, 4)
    order = np.argsort(ids, kind="stable")
    landmarks = LandmarkMap(np.array(ids, dtype=np.int64)[order], table[order, :2])
    return landmarks, table[order, 2:].copy()


def load_mrclam(folder: PathLike, robot: int = 1) -> MRCLAMRun:
    """Read one robot's drive from an MRCLAM data set folder (``Barcodes.dat``, ``Landmark_Groundtruth.dat``,
    ``Robot{robot}_Odometry.dat``, ``Robot{robot}_Measurement.dat``).

    Raises ``FileNotFoundError`` naming a missing file and ``ValueError`` when a landmark has no barcode or a
    robot subject is listed as a landmark.
    """
    folder = Path(folder)
    if robot not in ROBOT_SUBJECTS:
        raise ValueError(f"robot must be one of {ROBOT_SUBJECTS}, got {robot!r}")
    names = {
        "barcodes": "Barcodes.dat",
        "landmarks": "Landmark_Groundtruth.dat",
        "odometry": f"Robot{robot}_Odometry.dat",
        "measurements": f"Robot{robot}_Measurement.dat",
    }
    for name in names.values():
        if not (folder / name).is_file():
            raise FileNotFoundError(
                f"{folder / name} does not exist (an MRCLAM data set folder holds {name})"
            )
    barcodes = read_barcodes(folder / names["barcodes"])
    landmarks, landmark_std = read_landmark_truth(folder / names["landmarks"])
    robots = sorted(set(landmarks.ids.tolist()) & set(ROBOT_SUBJECTS))
    if robots:
        raise ValueError(f"{folder / names['landmarks']}: subjects {robots} are robots, not landmarks")
    missing = sorted(set(landmarks.ids.tolist()) - set(barcodes))
    if missing:
        raise ValueError(f"{folder / names['barcodes']}: landmark subjects {missing} have no barcode")
    return MRCLAMRun(
        robot=robot,
        odometry=read_odometry(folder / names["odometry"]),
        measurements=read_measurements(folder / names["measurements"]),
        barcodes=barcodes,
        landmarks=landmarks,
        landmark_std=landmark_std,
    )
