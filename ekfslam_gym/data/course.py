"""Readers and writers for the Freiburg "Robot Mapping" EKF-SLAM text formats (its EKF-SLAM exercise).

``sensor_data.dat`` is a sequence of blocks: one ``ODOMETRY r1 t r2`` line (odometry motion model: rad, m,
rad) followed by zero or more ``SENSOR id range bearing`` lines (1-based landmark id, m, rad in the robot
frame). ``world.dat`` holds one ``id x y`` line per ground-truth landmark.

Every block is read, the last one included (the course's Octave reader drops it: 330 steps instead of 331).
Values are kept exactly as written: the course file has a negative range and bearings outside (-pi, pi],
which are real data; the filter wraps the innovation, not the reading. Malformed lines raise ``ValueError``
with ``file:line`` in the message so a broken file is found without a debugger.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

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


def _lines(path: Path) -> Iterator[tuple[int, list[str]]]:
    """Yield (1-based line number, tokens) for the non-blank lines of a file."""
    with path.open("r", encoding="ascii", errors="replace") as handle:
        for number, line in enumerate(handle, start=1):
            tokens = line.split()
            if tokens:
                yield number, tokens


def _float(token: str, what: str, where: str) -> float:
    try:
        value = float(token)
    except ValueError:
        raise ValueError(f"{where}: {what} {token!r} is not a number") from None
    if not math.isfinite(value):
        raise ValueError(f"{where}: {what} {token!r} is not finite")
    return value


def _id(token: str, where: str) -> int:
    try:
        value = int(token)
    except ValueError:
        raise ValueError(f"{where}: landmark id {token!r} is not an integer") from None
    if value < 1:
        raise ValueError(f"{where}: landmark id {value} is not 1-based (must be >= 1)")
    return value


def _expect(tokens: list[str], count: int, where: str) -> None:
    if len(tokens) != count:
        raise ValueError(
            f"{where}: {tokens[0]} line needs {count - 1} values, got {len(tokens) - 1}: {' '.join(tokens)!r}"
        )


def read_sensor_data(path: PathLike) -> CourseData:
    """Read every block of a ``sensor_data.dat`` file (331 steps for the course file)."""
    path = Path(path)
    steps: list[Step] = []
    odometry: list[float] | None = None
    ids: list[int] = []
    z: list[list[float]] = []

    def flush() -> None:
        if odometry is not None:
            steps.append(Step(np.array(odometry), np.array(ids, dtype=np.int64), np.array(z).reshape(-1, 2)))

    for number, tokens in _lines(path):
        where = f"{path}:{number}"
        tag = tokens[0]
        if tag == "ODOMETRY":
            _expect(tokens, 4, where)
            values = [_float(t, name, where) for t, name in zip(tokens[1:], ("r1", "t", "r2"), strict=True)]
            flush()
            odometry, ids, z = values, [], []
        elif tag == "SENSOR":
            _expect(tokens, 4, where)
            if odometry is None:
                raise ValueError(f"{where}: SENSOR line before any ODOMETRY line")
            ids.append(_id(tokens[1], where))
            z.append([_float(tokens[2], "range", where), _float(tokens[3], "bearing", where)])
        else:
            raise ValueError(f"{where}: unknown tag {tag!r} (expected ODOMETRY or SENSOR)")
    flush()  # the last block too: the course's reader drops it, we do not
    return CourseData(steps)


def read_world(path: PathLike) -> LandmarkMap:
    """Read a ``world.dat`` file: one ``id x y`` line per landmark, ids distinct and 1-based."""
    path = Path(path)
    ids: list[int] = []
    positions: list[list[float]] = []
    first_line: dict[int, int] = {}
    for number, tokens in _lines(path):
        where = f"{path}:{number}"
        if len(tokens) != 3:
            raise ValueError(
                f"{where}: world line needs 3 values (id x y), got {len(tokens)}: {' '.join(tokens)!r}"
            )
        landmark = _id(tokens[0], where)
        if landmark in first_line:
            raise ValueError(
                f"{where}: landmark id {landmark} already defined on line {first_line[landmark]}"
            )
        first_line[landmark] = number
        ids.append(landmark)
        positions.append([_float(tokens[1], "x", where), _float(tokens[2], "y", where)])
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
    with path.open("w", encoding="ascii", newline="\n") as handle:
        handle.writelines(_format_steps(data.steps))
    return path


def write_world(path: PathLike, world: LandmarkMap) -> Path:
    """Write ``world`` in the ``world.dat`` format (file order kept); reading it back is exact."""
    path = Path(path)
    with path.open("w", encoding="ascii", newline="\n") as handle:
        for landmark, (x, y) in zip(world.ids, world.positions, strict=True):
            handle.write(f"{int(landmark)} {_fmt(x)} {_fmt(y)}\n")
    return path
