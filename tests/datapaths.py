"""Where the tests find the shared data sets (never copied into the repository)."""

from __future__ import annotations

import os
from pathlib import Path

# The course data lives in ../shared/data/freiburg beside the repository (see its README.md there).
_DEFAULT_FREIBURG = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "freiburg"
_DEFAULT_VICTORIA_PARK = _DEFAULT_FREIBURG.parent / "victoria_park" / "victoria_park.txt"


def victoria_park_file() -> Path | None:
    """GTSAM's victoria_park.txt: $EKFSLAM_VICTORIA_PARK if set, else ../shared/data/victoria_park beside the
    repository; None when absent."""
    path = Path(os.environ.get("EKFSLAM_VICTORIA_PARK", _DEFAULT_VICTORIA_PARK))
    return path if path.is_file() else None


def freiburg_dir() -> Path | None:
    """The Freiburg data folder: $EKFSLAM_DATA_DIR (the folder itself, or one holding ``freiburg/``) if set,
    else ../shared/data/freiburg beside the repository; None when neither exists."""
    env = os.environ.get("EKFSLAM_DATA_DIR")
    candidates = [Path(env), Path(env) / "freiburg"] if env else [_DEFAULT_FREIBURG]
    for candidate in candidates:
        if candidate.is_dir() and (any(candidate.glob("*.g2o")) or any(candidate.glob("*.dat"))):
            return candidate
    return None


_DEFAULT_MRCLAM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "mrclam"


def mrclam_dir() -> Path | None:
    """The MRCLAM data set 1 folder: $EKFSLAM_MRCLAM_DIR if set, else ../shared/data/mrclam beside the
    repository; None when it lacks robot 1's files."""
    env = os.environ.get("EKFSLAM_MRCLAM_DIR")
    folder = Path(env) if env else _DEFAULT_MRCLAM
    names = ("Barcodes.dat", "Landmark_Groundtruth.dat", "Robot1_Odometry.dat", "Robot1_Measurement.dat")
    return folder if all((folder / name).is_file() for name in names) else None
