"""The greedy planner's grid kernels: where its sensor has looked, the wall memory built from the wall scan, and
shortest-path distances to the unexplored around the remembered walls (compiled: they run every step)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ekfslam_gym.angles import compiled_wrap_angle as wrap_angle


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
def behind_wall(wall, xmin, ymin, cell, x, y, tx, ty):
    """Whether the straight line from (x, y) to (tx, ty) crosses a wall cell before the target's own cell."""
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
def mark_seen(seen, hidden, wall, xmin, ymin, cell, x, y, theta, max_range, half_fov):
    """Mark the cells wholly within range and field of view of (x, y, theta) whose centres no remembered
    wall hides; count in ``hidden`` how often each cell was in view but hidden. Returns the number of newly
    marked cells."""
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
    ``tag`` in ``stamp``, so no clearing is needed between calls)."""
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
    """Occupancy-style wall memory from one scan: clear the cells each beam crossed, then mark the cells its
    end point and the surfaces between neighbouring end points (closer than ``join`` m) fall in. Clearing
    first reopens a doorway that an earlier scan joined across, once a beam passes through it."""
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
def distance_field(start_cost, wall, cell, max_sweeps):
    """Multi-source shortest path lengths (m) through the non-wall cells: d(p) = min over sources u of
    start_cost(u) + path length(u, p), 8-connected (no corner cutting past a wall), by alternating forward and
    backward chamfer sweeps until nothing changes. ``start_cost`` is inf where a cell is not a source."""
    ny, nx = wall.shape
    d = start_cost.copy()
    diagonal = cell * math.sqrt(2.0)
    for _ in range(max_sweeps):
        changed = False
        for direction in (1, -1):
            rows = range(ny) if direction == 1 else range(ny - 1, -1, -1)
            for row in rows:
                cols = range(nx) if direction == 1 else range(nx - 1, -1, -1)
                for col in cols:
                    if wall[row, col]:
                        continue
                    best = d[row, col]
                    for dr, dc in ((-direction, -1), (-direction, 0), (-direction, 1), (0, -direction)):
                        r, c = row + dr, col + dc
                        if r < 0 or r >= ny or c < 0 or c >= nx or wall[r, c]:
                            continue
                        if dr != 0 and dc != 0:
                            if wall[row + dr, col] or wall[row, col + dc]:
                                continue
                            step = diagonal
                        else:
                            step = cell
                        if d[r, c] + step < best:
                            best = d[r, c] + step
                    if best < d[row, col]:
                        d[row, col] = best
                        changed = True
        if not changed:
            break
    return d


def frontier_field(
    open_cells: np.ndarray, wall: np.ndarray, cell: float, frontier_scale: float
) -> np.ndarray:
    """Distance (m) to the unexplored, around remembered walls, plus a cost for thin regions: every open
    unlooked-at cell is a source with cost -frontier_scale * ln(the fraction of open cells in the
    surrounding 4 m), so a large unexplored region beats a nearer sliver along a wall."""
    from scipy import ndimage

    width = max(1, int(round(4.0 / cell)))
    density = ndimage.uniform_filter(open_cells.astype(float), size=width, mode="constant")
    start = np.where(open_cells, -frontier_scale * np.log(np.maximum(density, 1e-3)), np.inf)
    return distance_field(start, wall, cell, 64)
