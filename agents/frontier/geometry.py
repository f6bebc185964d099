"""The frontier planner's geometry: grid cells and their centres, bearings from the robot's heading, landmarks in
the sensor's view, and points in the robot's frame. Poses are (x, y, heading), m and rad; the grid is the
coverage memory's (``ekfslam_gym.agents.navigation``)."""

from __future__ import annotations

import math

import numpy as np


def cell_of(
    x: float, y: float, xmin: float, ymin: float, cell: float, shape: tuple[int, int]
) -> tuple[int, int]:
    """The (row, col) of the grid of ``shape`` whose cell holds (x, y), clamped to the grid."""
    ny, nx = shape
    col = min(max(int(math.floor((x - xmin) / cell)), 0), nx - 1)
    row = min(max(int(math.floor((y - ymin) / cell)), 0), ny - 1)
    return row, col


def cell_centres(
    rows: np.ndarray, cols: np.ndarray, xmin: float, ymin: float, cell: float
) -> tuple[np.ndarray, np.ndarray]:
    """The centres (xs, ys), m, of the cells (rows, cols)."""
    return xmin + (cols + 0.5) * cell, ymin + (rows + 0.5) * cell


def bearings(pose: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """The absolute angles (rad, [0, pi]) between the heading of ``pose`` and the directions to the points."""
    return np.abs((np.arctan2(ys - pose[1], xs - pose[0]) - pose[2] + np.pi) % (2 * np.pi) - np.pi)


def in_reach(pose: np.ndarray, point: np.ndarray, reach: float, half_fov: float) -> bool:
    """Whether ``point`` lies within ``reach`` m of ``pose`` and within ``half_fov`` rad of its heading."""
    dx, dy = point[0] - pose[0], point[1] - pose[1]
    bearing = abs((math.atan2(dy, dx) - pose[2] + math.pi) % (2 * math.pi) - math.pi)
    return math.hypot(dx, dy) <= reach and bearing <= half_fov


def in_view(pose: np.ndarray, points: np.ndarray, max_range: float, half_fov: float) -> np.ndarray:
    """Which ``points`` (n, 2) lie within the sensor's ``max_range`` m and field of view (``half_fov`` rad each
    side of the heading) from ``pose`` (bool, n)."""
    delta = points - pose[:2]
    bearing = np.abs((np.arctan2(delta[:, 1], delta[:, 0]) - pose[2] + np.pi) % (2 * np.pi) - np.pi)
    return (np.hypot(delta[:, 0], delta[:, 1]) <= max_range) & (bearing <= half_fov)


def in_robot_frame(pose: np.ndarray, point: np.ndarray) -> tuple[float, float]:
    """``point`` (world, m) as (forward, left) m relative to ``pose`` (x, y, heading)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = point[0] - pose[0], point[1] - pose[1]
    return c * dx + s * dy, -s * dx + c * dy
