"""The project's own simulated drive, in the course's data format.

A robot drives ``laps`` times around a rounded rectangle among landmarks scattered in a ~10 x 10 m field,
starting at the origin with heading 0 (the pose the course's filter assumes, with zero covariance). Odometry
is reported in the odometry motion model (r1, t, r2) with small Gaussian noise; range-bearing readings of
the landmarks within ``max_range`` (and the optional field of view) carry Gaussian noise of sigma 0.1 m and
0.1 rad, which is what the course's measurement model Q = 0.01 I assumes. Ids are 1-based as in the course
files. Everything is drawn from one ``numpy.random.Generator`` seeded by ``seed``: the same seed gives the
same drive, bit for bit.

This is what ``python -m ekfslam_gym.replay`` replays by default; ``python -m ekfslam_gym.data.drive DIR``
writes it as ``sensor_data.dat`` and ``world.dat``.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ekfslam_gym.data.course import CourseData, LandmarkMap, PathLike, Step, write_sensor_data, write_world

__all__ = ["Drive", "loop_poses", "simulate_drive"]


@dataclass(frozen=True)
class Drive:
    """A simulated drive: the data the filter sees plus the truth it does not."""

    data: CourseData  # odometry and readings, one step per motion
    poses: np.ndarray  # (T+1, 3) true poses; poses[k+1] is where the readings of step k were taken
    world: LandmarkMap  # true landmarks, ids 1..n
    seed: int | None = None

    def write(self, directory: PathLike) -> tuple[Path, Path]:
        """Write ``sensor_data.dat`` and ``world.dat`` into ``directory`` (created if needed)."""
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        return (
            write_sensor_data(directory / "sensor_data.dat", self.data),
            write_world(directory / "world.dat", self.world),
        )


def _wrap(angle: np.ndarray | float) -> np.ndarray:
    """Wrap to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), 2.0 * np.pi)


def loop_poses(
    n_steps: int, *, width: float = 7.0, height: float = 6.0, corner_radius: float = 1.5, laps: float = 1.0
) -> np.ndarray:
    """Poses at ``n_steps + 1`` equally spaced points along ``laps`` counter-clockwise rounded-rectangle laps.

    The loop starts at the origin heading along +x, in the middle of its bottom edge, so the rectangle spans
    x in [-width/2, width/2] and y in [0, height]. Returns (n_steps + 1, 3) poses (x, y, heading).
    """
    if not 0.0 < corner_radius <= min(width, height) / 2.0:
        raise ValueError("corner_radius must be in (0, min(width, height) / 2]")
    half_straight = width / 2.0 - corner_radius
    side = height - 2.0 * corner_radius
    quarter = 0.5 * math.pi * corner_radius
    # (length, kind) of the pieces from the start point, counter-clockwise; kind 0 = straight, 1 = left arc.
    pieces = [
        (half_straight, 0),
        (quarter, 1),
        (side, 0),
        (quarter, 1),
        (2.0 * half_straight, 0),
        (quarter, 1),
        (side, 0),
        (quarter, 1),
        (half_straight, 0),
    ]
    perimeter = sum(length for length, _ in pieces)
    s = np.linspace(0.0, laps * perimeter, n_steps + 1)
    s_lap = np.mod(s, perimeter)
    s_lap[-1] = perimeter if laps == round(laps) else s_lap[-1]  # end exactly on the start of the loop

    poses = np.empty((n_steps + 1, 3))
    x, y, heading, start = 0.0, 0.0, 0.0, 0.0
    for length, kind in pieces:
        inside = (s_lap >= start) & (s_lap <= start + length)
        u = s_lap[inside] - start
        if kind == 0:
            poses[inside] = np.column_stack(
                [x + u * math.cos(heading), y + u * math.sin(heading), np.full(len(u), heading)]
            )
            x, y = x + length * math.cos(heading), y + length * math.sin(heading)
        else:
            theta = heading + u / corner_radius
            poses[inside] = np.column_stack(
                [
                    x + corner_radius * (np.sin(theta) - math.sin(heading)),
                    y - corner_radius * (np.cos(theta) - math.cos(heading)),
                    theta,
                ]
            )
            end = heading + length / corner_radius
            x += corner_radius * (math.sin(end) - math.sin(heading))
            y -= corner_radius * (math.cos(end) - math.cos(heading))
            heading = end
        start += length
    poses[:, 2] = _wrap(poses[:, 2])
    if laps == round(laps):
        poses[-1] = poses[0]  # close the loop exactly, not to within rounding
    return poses


def _odometry_between(poses: np.ndarray) -> np.ndarray:
    """Exact (r1, t, r2) that takes each pose to the next one, shape (T, 3)."""
    delta = np.diff(poses[:, :2], axis=0)
    t = np.hypot(delta[:, 0], delta[:, 1])
    r1 = _wrap(np.arctan2(delta[:, 1], delta[:, 0]) - poses[:-1, 2])
    r2 = _wrap(poses[1:, 2] - poses[:-1, 2] - r1)
    return np.column_stack([r1, t, r2])


def _scatter_landmarks(
    rng: np.random.Generator,
    n: int,
    path_xy: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    min_separation: float,
    clearance: float,
    reach: float,
) -> np.ndarray:
    """Rejection-sample n landmarks: apart from each other, off the path, but within sight of it."""
    landmarks = np.empty((0, 2))
    budget = 200 * n + 10_000  # candidates; generous for any sensible layout, quick to give up on a bad one
    while len(landmarks) < n and budget > 0:
        batch = rng.uniform(low, high, size=(256, 2))
        budget -= len(batch)
        to_path = np.min(np.linalg.norm(batch[:, None, :] - path_xy[None, :, :], axis=2), axis=1)
        for candidate in batch[(to_path >= clearance) & (to_path <= reach)]:
            if len(landmarks) and np.min(np.linalg.norm(landmarks - candidate, axis=1)) < min_separation:
                continue
            landmarks = np.vstack([landmarks, candidate])
            if len(landmarks) == n:
                break
    if len(landmarks) < n:
        raise ValueError(f"could not place {n} landmarks with these separation and clearance constraints")
    return landmarks


def simulate_drive(
    seed: int | None = 0,
    *,
    n_landmarks: int = 16,
    laps: int = 2,
    width: float = 7.0,
    height: float = 6.0,
    corner_radius: float = 1.5,
    field_size: float = 10.0,
    step_length: float = 0.1,
    max_range: float = 4.0,
    fov: float | None = None,
    odometry_std: Sequence[float] = (0.005, 0.005, 0.005),
    measurement_std: Sequence[float] = (0.1, 0.1),
    min_separation: float = 1.0,
    clearance: float = 0.5,
) -> Drive:
    """Generate a drive from ``seed``.

    Args:
        seed: seed of the ``numpy.random.Generator`` that draws the landmarks and all noise.
        n_landmarks: number of landmarks, ids 1..n_landmarks.
        laps: laps of the loop; more than one gives loop closures.
        width, height, corner_radius: the rounded rectangle [m], see :func:`loop_poses`.
        field_size: side [m] of the square field, centred on the loop, in which landmarks are scattered.
        step_length: nominal distance [m] between steps (the course's is 0.1).
        max_range: sensor range [m]; each landmark is placed within it of the path, so all get seen.
        fov: full field of view [rad] centred on the heading, or None for all around (as in the course).
        odometry_std: standard deviations of the reported (r1 [rad], t [m], r2 [rad]).
        measurement_std: standard deviations of the readings (range [m], bearing [rad]).
        min_separation: minimum distance [m] between landmarks.
        clearance: minimum distance [m] from a landmark to the path (keeps ranges away from 0).
    """
    if n_landmarks < 0 or laps < 1 or step_length <= 0.0 or max_range <= 0.0:
        raise ValueError("need n_landmarks >= 0, laps >= 1, step_length > 0 and max_range > 0")
    rng = np.random.default_rng(seed)

    perimeter = 2.0 * (width + height) - 8.0 * corner_radius + 2.0 * math.pi * corner_radius
    n_steps = max(1, round(laps * perimeter / step_length))
    poses = loop_poses(n_steps, width=width, height=height, corner_radius=corner_radius, laps=laps)

    centre = np.array([0.0, height / 2.0])
    dense = loop_poses(500, width=width, height=height, corner_radius=corner_radius)[:, :2]
    landmarks = _scatter_landmarks(
        rng,
        n_landmarks,
        dense,
        centre - field_size / 2.0,
        centre + field_size / 2.0,
        min_separation,
        clearance,
        0.9 * max_range,
    )
    ids = np.arange(1, n_landmarks + 1, dtype=np.int64)

    odometry = _odometry_between(poses) + rng.normal(0.0, 1.0, (n_steps, 3)) * np.asarray(odometry_std, float)

    steps = []
    for k in range(n_steps):
        x, y, theta = poses[k + 1]
        delta = landmarks - np.array([x, y])
        ranges = np.hypot(delta[:, 0], delta[:, 1])
        bearings = _wrap(np.arctan2(delta[:, 1], delta[:, 0]) - theta)
        seen = ranges <= max_range
        if fov is not None:
            seen &= np.abs(bearings) <= fov / 2.0
        z = np.column_stack([ranges[seen], bearings[seen]])
        # noise is added after wrapping, as in the course file: a bearing may leave (-pi, pi] slightly.
        z = z + rng.normal(0.0, 1.0, z.shape) * np.asarray(measurement_std, float)
        steps.append(Step(odometry[k], ids[seen], z))

    return Drive(CourseData(steps), poses, LandmarkMap(ids, landmarks), seed)


def main(argv: Sequence[str] | None = None) -> int:
    """Write a simulated drive as course files: ``python -m ekfslam_gym.data.drive DIR [--seed S]``."""
    parser = argparse.ArgumentParser(prog="python -m ekfslam_gym.data.drive", description=main.__doc__)
    parser.add_argument("directory", type=Path, help="where to write sensor_data.dat and world.dat")
    parser.add_argument("--seed", type=int, default=0, help="seed of the drive (default 0)")
    args = parser.parse_args(argv)
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
