"""Where a sensor has looked: the cells wholly within its range and field of view, marked on a coverage grid or
counted for a planned path, hidden behind the wall memory. Grid convention: ``ekfslam_gym.agents.navigation``."""

from __future__ import annotations

import math

from numba import njit

from ekfslam_gym.angles import compiled_wrap_angle as wrap_angle

from .walls import behind_wall


@njit(cache=True)
def cell_in_view(dx, dy, theta, min_range, max_range, half_fov, half_diag):
    """Whether all of a cell (centre at (dx, dy) from the sensor, half diagonal ``half_diag`` m) lies within
    range and field of view: conservative, so a landmark anywhere in a marked cell would have been read."""
    dist = math.sqrt(dx * dx + dy * dy)
    if dist + half_diag > max_range or dist - half_diag < min_range:
        return False
    if half_fov >= math.pi:
        return True
    bearing = wrap_angle(math.atan2(dy, dx) - theta)
    return abs(bearing) + math.asin(min(1.0, half_diag / dist)) <= half_fov


@njit(cache=True)
def mark_seen(seen, hidden, wall, xmin, ymin, cell, x, y, theta, max_range, half_fov):
    """Mark in ``seen`` (bool grid) the cells wholly within range and field of view of (x, y, theta) whose
    centres no remembered wall hides; count in ``hidden`` (int grid) how often each cell was in view but hidden.
    Returns the number of newly marked cells."""
    ny, nx = seen.shape
    c0 = max(0, int((x - max_range - xmin) / cell))
    c1 = min(nx - 1, int((x + max_range - xmin) / cell))
    r0 = max(0, int((y - max_range - ymin) / cell))
    r1 = min(ny - 1, int((y + max_range - ymin) / cell))
    half_diag = cell * math.sqrt(0.5)
    marked = 0
    for row in range(r0, r1 + 1):
        cy = ymin + (row + 0.5) * cell
        for col in range(c0, c1 + 1):
            if seen[row, col] or wall[row, col]:
                continue
            cx = xmin + (col + 0.5) * cell
            if not cell_in_view(cx - x, cy - y, theta, 0.0, max_range, half_fov, half_diag):
                continue
            if behind_wall(wall, xmin, ymin, cell, x, y, cx, cy):
                hidden[row, col] += 1
                continue
            seen[row, col] = True
            marked += 1
    return marked


@njit(cache=True)
def count_new(seen, stamp, tag, xmin, ymin, cell, poses, min_range, max_range, half_fov):
    """Unseen cells wholly in view of any of ``poses`` (K, 3), each counted once (cells counted are set to
    ``tag`` in ``stamp``, an int grid, so no clearing is needed between calls)."""
    ny, nx = seen.shape
    half_diag = cell * math.sqrt(0.5)
    count = 0
    for k in range(poses.shape[0]):
        x, y, theta = poses[k, 0], poses[k, 1], poses[k, 2]
        c0 = max(0, int((x - max_range - xmin) / cell))
        c1 = min(nx - 1, int((x + max_range - xmin) / cell))
        r0 = max(0, int((y - max_range - ymin) / cell))
        r1 = min(ny - 1, int((y + max_range - ymin) / cell))
        for row in range(r0, r1 + 1):
            dy = ymin + (row + 0.5) * cell - y
            for col in range(c0, c1 + 1):
                if seen[row, col] or stamp[row, col] == tag:
                    continue
                dx = xmin + (col + 0.5) * cell - x
                if cell_in_view(dx, dy, theta, min_range, max_range, half_fov, half_diag):
                    stamp[row, col] = tag
                    count += 1
    return count
