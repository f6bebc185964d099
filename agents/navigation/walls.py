"""The wall memory: an occupancy-style wall grid built from wall scans (the planners never read the walls' true
geometry), and straight lines checked against it. Grid convention: ``ekfslam_gym.agents.navigation``."""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def paint(grid, xmin, ymin, cell, x0, y0, x1, y1, value):
    """Set the cells along the segment (x0, y0)-(x1, y1) to ``value`` (samples every quarter cell; points left of
    or below the grid fall outside it, not into its first cell)."""
    ny, nx = grid.shape
    n = int(math.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2) / (0.25 * cell)) + 1
    for i in range(n + 1):
        t = i / n
        col = int(math.floor((x0 + t * (x1 - x0) - xmin) / cell))
        row = int(math.floor((y0 + t * (y1 - y0) - ymin) / cell))
        if 0 <= row < ny and 0 <= col < nx:
            grid[row, col] = value


@njit(cache=True)
def update_walls(wall, xmin, ymin, cell, x, y, theta, angles, scan, scan_max, join):
    """Occupancy-style wall memory from one scan taken at pose (x, y, theta): clear the cells each beam crossed,
    then mark the cells its end point and the surfaces between neighbouring end points (closer than ``join`` m)
    fall in. Beams of ``scan`` (m) at ``angles`` (rad from the heading); a range >= ``scan_max`` hit nothing.
    Clearing first reopens a doorway that an earlier scan joined across, once a beam passes through it."""
    n = scan.shape[0]
    half = 0.5 * cell
    for i in range(n):
        reach = scan[i] - half
        if reach > 0.0:
            a = theta + angles[i]
            paint(wall, xmin, ymin, cell, x, y, x + reach * math.cos(a), y + reach * math.sin(a), False)
    for i in range(n):
        if scan[i] >= scan_max:
            continue
        a = theta + angles[i]
        px, py = x + scan[i] * math.cos(a), y + scan[i] * math.sin(a)
        paint(wall, xmin, ymin, cell, px, py, px, py, True)
        k = (i + 1) % n
        if scan[k] < scan_max:
            b = theta + angles[k]
            qx, qy = x + scan[k] * math.cos(b), y + scan[k] * math.sin(b)
            if (qx - px) ** 2 + (qy - py) ** 2 < join * join:
                paint(wall, xmin, ymin, cell, px, py, qx, qy, True)


@njit(cache=True)
def behind_wall(wall, xmin, ymin, cell, x, y, tx, ty):
    """Whether the straight line from (x, y) to (tx, ty) crosses a wall cell before the target's own cell
    (sampled every half cell)."""
    ny, nx = wall.shape
    target_col = int((tx - xmin) / cell)
    target_row = int((ty - ymin) / cell)
    n = int(math.sqrt((tx - x) ** 2 + (ty - y) ** 2) / (0.5 * cell)) + 1
    for i in range(n):
        t = i / n
        col = int((x + t * (tx - x) - xmin) / cell)
        row = int((y + t * (ty - y) - ymin) / cell)
        if row == target_row and col == target_col:
            return False
        if 0 <= row < ny and 0 <= col < nx and wall[row, col]:
            return True
    return False


@njit(cache=True)
def line_is_free(wall, xmin, ymin, cell, x0, y0, x1, y1):
    """Whether the segment (x0, y0)-(x1, y1) crosses no wall cell (sampled every quarter cell; the start cell is
    not checked, so a robot next to a wall can still see away from it)."""
    ny, nx = wall.shape
    c0 = int(math.floor((x0 - xmin) / cell))
    r0 = int(math.floor((y0 - ymin) / cell))
    n = int(math.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2) / (0.25 * cell)) + 1
    for i in range(1, n + 1):
        t = i / n
        col = int(math.floor((x0 + t * (x1 - x0) - xmin) / cell))
        row = int(math.floor((y0 + t * (y1 - y0) - ymin) / cell))
        if (row != r0 or col != c0) and 0 <= row < ny and 0 <= col < nx and wall[row, col]:
            return False
    return True
