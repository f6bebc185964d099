"""TUM trajectory files and landmark CSVs, so that trajectories can be judged with the evo tools.

A TUM trajectory file (the TUM RGB-D benchmark's format, read by ``evo_ape tum`` and ``evo_traj tum``) holds
one pose per line::

    timestamp tx ty tz qx qy qz qw

in seconds, metres and a unit quaternion (scalar last). This project's poses are planar (x, y, heading): they
are written with z = 0 and the heading as a rotation about z, q = (0, 0, sin(theta / 2), cos(theta / 2));
reading keeps x, y and the yaw of the quaternion. Positions and quaternions are written with the shortest
digits that read back as the same float64 (``repr``), so evo's absolute pose error on the files is the
project's ``evaluation.metrics.ate`` to rounding, not to a print format; timestamps to the nanosecond.

The landmark CSV holds one row per landmark with its true and estimated position and whether the filter ever
saw it; an unseen landmark's estimate is ``nan``: the filter has not initialised it and holds only its prior
(docs/filter-and-graph.md, "The maths, briefly").
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

from .records import ENCODING, read_records

__all__ = [
    "LANDMARK_COLUMNS",
    "TUM_HEADER",
    "read_tum",
    "write_landmarks_csv",
    "write_tum",
    "yaw_quaternions",
]

TUM_HEADER = "# timestamp tx ty tz qx qy qz qw"
LANDMARK_COLUMNS = ("id", "true_x", "true_y", "estimated_x", "estimated_y", "seen")


def yaw_quaternions(theta: np.ndarray) -> np.ndarray:
    """(T, 4) unit quaternions (qx, qy, qz, qw) of rotations by ``theta`` rad about z."""
    half = 0.5 * np.asarray(theta, dtype=float).reshape(-1)
    zeros = np.zeros_like(half)
    return np.column_stack([zeros, zeros, np.sin(half), np.cos(half)])


def write_tum(path: str | os.PathLike[str], timestamps: np.ndarray, poses: np.ndarray) -> Path:
    """Write (T, 3) planar poses (x m, y m, theta rad) at the (T,) ``timestamps`` (s) as a TUM file."""
    timestamps = np.asarray(timestamps, dtype=float).reshape(-1)
    poses = np.asarray(poses, dtype=float)
    if poses.ndim != 2 or poses.shape[1] != 3 or len(poses) != len(timestamps):
        raise ValueError(f"need (T, 3) poses and (T,) timestamps, got {poses.shape} and {timestamps.shape}")
    if not np.all(np.isfinite(poses)):
        raise ValueError("poses must be finite (a TUM file has no missing value)")
    columns = np.column_stack([poses[:, :2], np.zeros(len(poses)), yaw_quaternions(poses[:, 2])])
    lines = [TUM_HEADER]
    for t, row in zip(timestamps.tolist(), columns.tolist()):
        lines.append(f"{t:.9f} " + " ".join(map(repr, row)))
    path = Path(path)
    path.write_text("\n".join(lines) + "\n", encoding=ENCODING)
    return path


def read_tum(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """``(timestamps (T,), poses (T, 3))`` of a TUM file: x, y and the yaw of each quaternion (z, roll and
    pitch are dropped). Raises ``ValueError`` naming the file and line when a line does not hold 8 numbers."""
    values = []
    for record in read_records(path):
        record.expect(8, "TUM (timestamp x y z qx qy qz qw)")
        values.append(record.numbers(0, "value"))
    rows = np.array(values, dtype=float).reshape(-1, 8)
    if rows.size == 0:
        return np.zeros(0), np.zeros((0, 3))
    qx, qy, qz, qw = rows[:, 4:].T
    yaw = np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    return rows[:, 0], np.column_stack([rows[:, 1], rows[:, 2], yaw])


def write_landmarks_csv(
    path: str | os.PathLike[str],
    true: np.ndarray,
    estimated: np.ndarray,
    seen: np.ndarray,
    ids: np.ndarray | None = None,
) -> Path:
    """Write ``LANDMARK_COLUMNS``, one row per landmark: ``ids`` (default the slot index 0..n-1), the (n, 2)
    true and estimated positions (``nan`` where not ``seen``) and ``seen`` as 0/1."""
    true = np.asarray(true, dtype=float).reshape(-1, 2)
    estimated = np.asarray(estimated, dtype=float).reshape(-1, 2)
    seen = np.asarray(seen, dtype=bool).reshape(-1)
    ids = np.arange(len(true)) if ids is None else np.asarray(ids).reshape(-1)
    if not len(estimated) == len(seen) == len(ids) == len(true):
        raise ValueError(
            f"lengths disagree: true {len(true)}, estimated {len(estimated)}, seen {len(seen)}, ids {len(ids)}"
        )
    estimated = np.where(seen[:, None], estimated, np.nan)
    path = Path(path)
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(LANDMARK_COLUMNS)
        positions = np.column_stack([true, estimated]).tolist()
        for i, xy, s in zip(ids.tolist(), positions, seen.tolist()):
            writer.writerow([i, *map(repr, xy), int(s)])
    return path
