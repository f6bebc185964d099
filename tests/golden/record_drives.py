"""Record the simulated drives that ``tests/data/test_drive.py`` and ``tests/graph/test_smoother.py`` hold the generators to.

Run once, before a refactor of ``ekfslam_gym/data/``, with ``python -m tests.golden.record_drives``: it writes
``drives.npz`` beside this file, every array of a few seeded drives (the course-format loop drive the replay
command and its tests use, and the smoother's waypoint drive). The generators promise the same drive for the
same seed, bit for bit, so the test compares exactly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
GOLDEN = HERE / "drives.npz"

# name -> (generator, keyword arguments)
LOOP_DRIVES: dict[str, dict] = {"loop0": {"seed": 0}, "loop3_fov": {"seed": 3, "fov": np.pi}}
WAYPOINT_DRIVES: dict[str, dict] = {"waypoint1": {"num_steps": 150, "num_landmarks": 15, "seed": 1}}


def loop_drive_arrays(**kwargs) -> dict[str, np.ndarray]:
    """Every array of ``simulate_drive(**kwargs)``: poses, landmarks, odometry, readings (flattened)."""
    from ekfslam_gym.data.synthetic import simulate_drive

    drive = simulate_drive(**kwargs)
    return {
        "poses": drive.poses,
        "landmark_ids": drive.world.ids,
        "landmarks": drive.world.positions,
        "odometry": np.array([step.odometry for step in drive.data]),
        "reading_counts": drive.data.readings_per_step(),
        "reading_ids": np.concatenate([step.ids for step in drive.data]),
        "readings": np.concatenate([step.z for step in drive.data]),
    }


def waypoint_drive_arrays(**kwargs) -> dict[str, np.ndarray]:
    """Every array of ``synthetic_drive(**kwargs)``."""
    from ekfslam_gym.data.synthetic import synthetic_drive

    drive = synthetic_drive(**kwargs)
    return {
        "poses": drive.true_poses,
        "landmarks": drive.landmarks,
        "odometry": drive.odometry,
        "odometry_cov": drive.odometry_cov,
        "reading_cov": drive.reading_cov,
        "reading_counts": np.array([len(r) for r in drive.readings]),
        "readings": np.concatenate(drive.readings),
    }


def recordings() -> dict[str, np.ndarray]:
    arrays = {}
    for name, kwargs in LOOP_DRIVES.items():
        arrays.update({f"{name}/{k}": v for k, v in loop_drive_arrays(**kwargs).items()})
    for name, kwargs in WAYPOINT_DRIVES.items():
        arrays.update({f"{name}/{k}": v for k, v in waypoint_drive_arrays(**kwargs).items()})
    return arrays


def main() -> None:
    np.savez_compressed(GOLDEN, **recordings())
    print(f"wrote {GOLDEN}")


if __name__ == "__main__":
    main()
