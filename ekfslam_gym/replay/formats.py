"""Which data set a path holds, for ``ekfslam-replay --data PATH`` without ``--dataset``: an MRCLAM folder holds
``Barcodes.dat``; a file whose first record is a GTSAM 2-D tag (``data.gtsam2d``) is a GTSAM file, one that
starts with the course's 4-field ``ODOMETRY`` (or ``SENSOR``) line a course file."""

from __future__ import annotations

import os
from pathlib import Path

from ..data.records import read_records

__all__ = ["DATASETS", "detect_dataset"]

DATASETS = ("course", "mrclam", "gtsam")

# the first tags of a GTSAM 2-D file (``data.gtsam2d``); the course's files start with a 4-field ODOMETRY line
_GTSAM_TAGS = (
    "VERTEX_SE2",
    "VERTEX2",
    "VERTEX",
    "VERTEX_XY",
    "ODOMETRY",
    "EDGE_SE2",
    "EDGE2",
    "EDGE",
    "LANDMARK",
    "BR",
)


def detect_dataset(data: str | os.PathLike[str] | None) -> str:
    """One of ``DATASETS``: ``course`` for no path (the simulated drive), a missing path or an unrecognised
    first line (the course reader then says what is wrong with it)."""
    if data is None:
        return "course"
    data = Path(data)
    if (data / "Barcodes.dat").is_file():
        return "mrclam"
    if data.is_file():
        first = next(read_records(data, comment=None), None)
        if first is not None:
            course = first.tokens[0] in ("ODOMETRY", "SENSOR") and len(first.tokens) == 4
            return "gtsam" if first.tokens[0] in _GTSAM_TAGS and not course else "course"
    return "course"
