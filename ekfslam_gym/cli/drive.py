"""``python -m ekfslam_gym.cli.drive DIR [--seed S]``: write the simulated drive as course files (see
``ekfslam_gym.data.synthetic``), for ``ekfslam-replay --data`` or the course's own code."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path


def main(argv: Sequence[str] | None = None) -> int:
    """Write a simulated drive as course files: ``python -m ekfslam_gym.cli.drive DIR [--seed S]``."""
    parser = argparse.ArgumentParser(prog="python -m ekfslam_gym.cli.drive", description=main.__doc__)
    parser.add_argument("directory", type=Path, help="where to write sensor_data.dat and world.dat")
    parser.add_argument("--seed", type=int, default=0, help="seed of the drive (default 0)")
    args = parser.parse_args(argv)
    from ..data.synthetic import simulate_drive

    drive = simulate_drive(args.seed)
    try:
        sensor_path, world_path = drive.write(args.directory)
    except OSError as error:
        parser.error(f"cannot write to {args.directory}: {error}")
    print(f"{len(drive.data)} steps, {drive.data.n_readings} readings, {len(drive.world)} landmarks")
    print(f"wrote {sensor_path} and {world_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
