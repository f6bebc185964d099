"""Seeded synthetic drives with known truth, the one module that makes them.

- ``simulate_drive``: the project's own drive in the course's data format. A robot drives ``laps`` times
  around a rounded rectangle among landmarks scattered in a ~10 x 10 m field, starting at the origin with
  heading 0 (the pose the course's filter assumes, with zero covariance). Odometry is reported in the odometry
  motion model (r1, t, r2) with small Gaussian noise; range-bearing readings of the landmarks within
  ``max_range`` (and the optional field of view) carry Gaussian noise of sigma 0.1 m and 0.1 rad, which is
  what the course's measurement model Q = 0.01 I assumes. Ids are 1-based as in the course files. This is
  what ``ekfslam-replay`` replays by default; ``python -m ekfslam_gym.cli.drive DIR`` writes it
  as ``sensor_data.dat`` and ``world.dat``.
- ``synthetic_drive``: a drive for testing and benchmarking the smoother and graph solver. A robot steers
  towards random waypoints in a square arena at constant step length; odometry (r1, t, r2) is the true motion
  plus Gaussian control noise M; readings are range and bearing of every landmark within range, plus Gaussian
  noise Q.

Both decompose the true motion with the simulator's own turn-drive-turn decomposition (``odometry_between``),
and all randomness comes from the ``seed`` argument: the same seed gives the same drive, bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..angles import wrap_angles
from ..graph.factors import range_bearing
from .course import CourseData, LandmarkMap, PathLike, Step, write_sensor_data, write_world

__all__ = ["Drive", "SyntheticDrive", "loop_poses", "odometry_between", "simulate_drive", "synthetic_drive"]


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
    poses[:, 2] = wrap_angles(poses[:, 2])
    if laps == round(laps):
        poses[-1] = poses[0]  # close the loop exactly, not to within rounding
    return poses


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

    odometry = odometry_between(poses) + rng.normal(0.0, 1.0, (n_steps, 3)) * np.asarray(odometry_std, float)

    steps = []
    for k in range(n_steps):
        x, y, theta = poses[k + 1]
        delta = landmarks - np.array([x, y])
        ranges = np.hypot(delta[:, 0], delta[:, 1])
        bearings = wrap_angles(np.arctan2(delta[:, 1], delta[:, 0]) - theta)
        seen = ranges <= max_range
        if fov is not None:
            seen &= np.abs(bearings) <= fov / 2.0
        z = np.column_stack([ranges[seen], bearings[seen]])
        # noise is added after wrapping, as in the course file: a bearing may leave (-pi, pi] slightly.
        z = z + rng.normal(0.0, 1.0, z.shape) * np.asarray(measurement_std, float)
        steps.append(Step(odometry[k], ids[seen], z))

    return Drive(CourseData(steps), poses, LandmarkMap(ids, landmarks), seed)


Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)  # holds arrays
class SyntheticDrive:
    """Truth and measurements of a drive; `readings[t]` (k, 3) rows (landmark id, r, φ) are taken at pose t+1."""

    true_poses: Array  # (T+1, 3)
    landmarks: Array  # (N, 2)
    odometry: Array  # (T, 3) noisy (r1, t, r2)
    odometry_cov: Array  # (3, 3) M
    readings: list[Array]
    reading_cov: Array  # (2, 2) Q


def odometry_between(poses: np.ndarray) -> np.ndarray:
    """The exact (rot1, trans, rot2) from each pose (T+1, 3) to the next, (T, 3): the simulator's
    decomposition (``ekfslam_gym.sim.odometry.decompose_odometry``), with rot2 wrapped as course files hold it."""
    from ..sim.odometry import decompose_odometry

    out = np.empty((len(poses) - 1, 3))
    for t in range(len(poses) - 1):
        out[t] = decompose_odometry(*poses[t], *poses[t + 1])
    out[:, 2] = wrap_angles(out[:, 2])
    return out


def synthetic_drive(
    num_steps: int = 200,
    num_landmarks: int = 20,
    *,
    seed: int = 0,
    arena: float = 20.0,
    step_length: float = 0.5,
    max_turn: float = 0.3,
    max_range: float = 6.0,
    odometry_std: tuple[float, float, float] = (0.01, 0.02, 0.01),
    reading_std: tuple[float, float] = (0.05, 0.02),
) -> SyntheticDrive:
    """Generate a drive of `num_steps` steps among `num_landmarks` landmarks in an `arena`×`arena` m square.

    `max_turn` [rad] bounds the heading change per step; `odometry_std` is (σ_r1, σ_t, σ_r2) [rad, m, rad] and
    `reading_std` (σ_r, σ_φ) [m, rad].
    """
    rng = np.random.default_rng(seed)
    landmarks = rng.uniform(0.0, arena, size=(num_landmarks, 2))
    poses = np.empty((num_steps + 1, 3))
    poses[0] = (arena / 2, arena / 2, rng.uniform(-np.pi, np.pi))
    target = rng.uniform(0.1 * arena, 0.9 * arena, size=2)
    for t in range(num_steps):
        x, y, th = poses[t]
        if np.hypot(*(target - (x, y))) < 2 * step_length:
            target = rng.uniform(0.1 * arena, 0.9 * arena, size=2)
        turn = np.clip(wrap_angles(np.arctan2(target[1] - y, target[0] - x) - th), -max_turn, max_turn)
        r1 = 0.5 * turn
        heading = th + r1
        poses[t + 1] = (
            x + step_length * np.cos(heading),
            y + step_length * np.sin(heading),
            wrap_angles(th + turn),
        )

    true_controls = odometry_between(poses)
    M = np.diag(np.square(odometry_std))
    odometry = true_controls + rng.multivariate_normal(np.zeros(3), M, size=num_steps)

    Q = np.diag(np.square(reading_std))
    readings = []
    for t in range(1, num_steps + 1):
        z = range_bearing(np.repeat(poses[t][:, None], num_landmarks, axis=1), landmarks.T).T
        visible = np.flatnonzero(z[:, 0] < max_range)
        noisy = z[visible] + rng.multivariate_normal(np.zeros(2), Q, size=len(visible))
        noisy[:, 1] = wrap_angles(noisy[:, 1])
        readings.append(np.column_stack([visible.astype(float), noisy]))
    return SyntheticDrive(poses, landmarks, odometry, M, readings, Q)
