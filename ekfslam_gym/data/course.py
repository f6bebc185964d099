"""Readers and writers for the Freiburg "Robot Mapping" EKF-SLAM text formats (its EKF-SLAM exercise).

``sensor_data.dat`` is a sequence of blocks: one ``ODOMETRY r1 t r2`` line (odometry motion model: rad, m,
rad) followed by zero or more ``SENSOR id range bearing`` lines (1-based landmark id, m, rad in the robot
frame). ``world.dat`` holds one ``id x y`` line per ground-truth landmark.

Every block is read, the last one included (the course's Octave reader drops it: 330 steps instead of 331).
Values are kept exactly as written: the course file has a negative range and bearings outside (-pi, pi],
which are real data; the filter wraps the innovation, not the reading. Malformed lines raise ``ValueError``
with ``file:line`` in the message (``data.records``) so a broken file is found without a debugger.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .records import ENCODING, Record, read_records

__all__ = [
    "CourseData",
    "Step",
    "LandmarkMap",
    "read_sensor_data",
    "read_world",
    "write_sensor_data",
    "write_world",
]

PathLike = str | os.PathLike[str]


@dataclass(frozen=True)
class Step:
    """One block: the odometry that moved the robot, then the readings taken at the new pose."""

    odometry: np.ndarray  # (3,) float: r1 [rad], t [m], r2 [rad]
    ids: np.ndarray  # (m,) int: landmark ids as in the file (1-based)
    z: np.ndarray  # (m, 2) float: range [m], bearing [rad]

    def __post_init__(self) -> None:
        odometry = np.asarray(self.odometry, dtype=float).reshape(3)
        ids = np.asarray(self.ids, dtype=np.int64).reshape(-1)
        z = np.asarray(self.z, dtype=float).reshape(-1, 2)
        if len(ids) != len(z):
            raise ValueError(f"step has {len(ids)} ids but {len(z)} readings")
        object.__setattr__(self, "odometry", odometry)
        object.__setattr__(self, "ids", ids)
        object.__setattr__(self, "z", z)


@dataclass
class CourseData:
    """A whole drive: the steps in order (``len`` is the number of steps, i.e. of predictions)."""

    steps: list[Step] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.steps)

    def __iter__(self) -> Iterator[Step]:
        return iter(self.steps)

    def __getitem__(self, index: int) -> Step:
        return self.steps[index]

    @property
    def n_readings(self) -> int:
        """Total number of SENSOR readings over all steps."""
        return sum(len(step.ids) for step in self.steps)

    @property
    def max_id(self) -> int:
        """Largest landmark id seen (0 when there is no reading)."""
        return max((int(step.ids.max()) for step in self.steps if len(step.ids)), default=0)

    def readings_per_step(self) -> np.ndarray:
        """Number of readings in each step, shape (T,)."""
        return np.array([len(step.ids) for step in self.steps], dtype=np.int64)

    def head(self, n_steps: int) -> CourseData:
        """The first ``n_steps`` steps (the course framework's 330 is ``head(330)``)."""
        return CourseData(self.steps[:n_steps])


@dataclass(frozen=True)
class LandmarkMap:
    """The course's world file: ground-truth landmarks, in file order, used for plotting and evaluation and never
    given to the filter (not the simulator's ``ekfslam_gym.sim.World``, which is a whole physical world)."""

    ids: np.ndarray  # (n,) int, distinct
    positions: np.ndarray  # (n, 2) float [m]

    def __post_init__(self) -> None:
        ids = np.asarray(self.ids, dtype=np.int64).reshape(-1)
        positions = np.asarray(self.positions, dtype=float).reshape(-1, 2)
        if len(ids) != len(positions):
            raise ValueError(f"world has {len(ids)} ids but {len(positions)} positions")
        if len(np.unique(ids)) != len(ids):
            raise ValueError("world landmark ids are not distinct")
        object.__setattr__(self, "ids", ids)
        object.__setattr__(self, "positions", positions)

    def __len__(self) -> int:
        return len(self.ids)

    def as_dict(self) -> dict[int, np.ndarray]:
        """``{id: (x, y)}``."""
        return {int(i): p for i, p in zip(self.ids, self.positions, strict=True)}

    def sorted(self) -> LandmarkMap:
        """The same landmarks ordered by id: the order of the filter's landmark slots."""
        order = np.argsort(self.ids, kind="stable")
        return LandmarkMap(self.ids[order], self.positions[order])


# --------------------------------------------------------------------------------------------------- parsing


def _id(record: Record, index: int) -> int:
    value = record.integer(index, "landmark id")
    if value < 1:
        raise record.error(f"landmark id {value} is not 1-based (must be >= 1)")
    return value


def read_sensor_data(path: PathLike) -> CourseData:
    """Read every block of a ``sensor_data.dat`` file (331 steps for the course file)."""
    steps: list[Step] = []
    odometry: list[float] | None = None
    ids: list[int] = []
    z: list[list[float]] = []

    def flush() -> None:
        if odometry is not None:
            steps.append(Step(np.array(odometry), np.array(ids, dtype=np.int64), np.array(z).reshape(-1, 2)))

    for record in read_records(path, comment=None):
        tag = record.tokens[0]
        if tag == "ODOMETRY":
            record.expect(3, tag, tagged=True)
            values = [record.number(i, name) for i, name in enumerate(("r1", "t", "r2"), start=1)]
            flush()
            odometry, ids, z = values, [], []
        elif tag == "SENSOR":
            record.expect(3, tag, tagged=True)
            if odometry is None:
                raise record.error("SENSOR line before any ODOMETRY line")
            ids.append(_id(record, 1))
            z.append([record.number(2, "range"), record.number(3, "bearing")])
        else:
            raise record.error(f"unknown tag {tag!r} (expected ODOMETRY or SENSOR)")
    flush()  # the last block too: the course's reader drops it, we do not
    return CourseData(steps)


def read_world(path: PathLike) -> LandmarkMap:
    """Read a ``world.dat`` file: one ``id x y`` line per landmark, ids distinct and 1-based."""
    ids: list[int] = []
    positions: list[list[float]] = []
    first_line: dict[int, int] = {}
    for record in read_records(path, comment=None):
        record.expect(3, "world (id x y)")
        landmark = _id(record, 0)
        if landmark in first_line:
            raise record.error(f"landmark id {landmark} already defined on line {first_line[landmark]}")
        first_line[landmark] = record.line
        ids.append(landmark)
        positions.append([record.number(1, "x"), record.number(2, "y")])
    return LandmarkMap(np.array(ids, dtype=np.int64), np.array(positions, dtype=float).reshape(-1, 2))


# --------------------------------------------------------------------------------------------------- writing


def _fmt(value: float) -> str:
    # repr is the shortest string that reads back to the same double: the round trip is exact.
    return repr(float(value))


def _format_steps(steps: Iterable[Step]) -> Iterator[str]:
    for step in steps:
        yield "ODOMETRY " + " ".join(_fmt(v) for v in step.odometry) + "\n"
        for landmark, (r, phi) in zip(step.ids, step.z, strict=True):
            yield f"SENSOR {int(landmark)} {_fmt(r)} {_fmt(phi)}\n"


def write_sensor_data(path: PathLike, data: CourseData) -> Path:
    """Write ``data`` in the ``sensor_data.dat`` format; reading it back gives identical numbers."""
    path = Path(path)
    with path.open("w", encoding=ENCODING, newline="\n") as handle:
        handle.writelines(_format_steps(data.steps))
    return path


def write_world(path: PathLike, world: LandmarkMap) -> Path:
    """Write ``world`` in the ``world.dat`` format (file order kept); reading it back is exact."""
    path = Path(path)
    with path.open("w", encoding=ENCODING, newline="\n") as handle:
        for landmark, (x, y) in zip(world.ids, world.positions, strict=True):
            handle.write(f"{int(landmark)} {_fmt(x)} {_fmt(y)}\n")
    return path
