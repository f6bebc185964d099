"""Compiled 2-D geometry against the static wall segments: clearances, line of sight and ray casts.

Why not pymunk's ``segment_query_first``: one call costs ~1.5-2.6 µs through cffi on this machine, so occluding
the ~10 landmarks in range and casting 16 beams costs ~40-60 µs per step (``bench/sim.py``), twice the
simulator's whole budget. The walls never move, so the same tests run here over the (k, 4) segment array,
culled to the walls within reach first: ~1 µs of arithmetic for both, plus the call overhead
(``tests/sim/test_geometry.py`` cross-checks them against pymunk and against dense sampling).

A wall is a capsule: its centre-line segment ``[x1, y1, x2, y2]`` (metres) swept by ``wall_radius``, which is
exactly the shape of a ``pymunk.Segment`` with that radius. Angles are radians, wrapped to (-pi, pi].
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..angles import compiled_wrap_angle as wrap_angle
from ..kernel_types import BoolArray2, F8Array1, F8Array2, I8Array1

TWO_PI = 2.0 * math.pi


@njit(cache=True)
def _point_segment_dist2(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Squared distance from point p to segment ab (m^2)."""
    ex = bx - ax
    ey = by - ay
    len2 = ex * ex + ey * ey
    s = 0.0
    if len2 > 0.0:
        s = ((px - ax) * ex + (py - ay) * ey) / len2
        s = min(1.0, max(0.0, s))
    dx = ax + s * ex - px
    dy = ay + s * ey - py
    return dx * dx + dy * dy


@njit(cache=True)
def _orient(ax: float, ay: float, bx: float, by: float, cx: float, cy: float) -> float:
    """Twice the signed area of triangle abc: > 0 if c is left of ab."""
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@njit(cache=True)
def _segment_segment_dist2(
    px: float, py: float, qx: float, qy: float, ax: float, ay: float, bx: float, by: float
) -> float:
    """Squared distance between segments pq and ab (m^2): 0 if they cross."""
    d1 = _orient(ax, ay, bx, by, px, py)
    d2 = _orient(ax, ay, bx, by, qx, qy)
    d3 = _orient(px, py, qx, qy, ax, ay)
    d4 = _orient(px, py, qx, qy, bx, by)
    if ((d1 > 0.0 and d2 < 0.0) or (d1 < 0.0 and d2 > 0.0)) and (
        (d3 > 0.0 and d4 < 0.0) or (d3 < 0.0 and d4 > 0.0)
    ):
        return 0.0
    return min(
        min(_point_segment_dist2(px, py, ax, ay, bx, by), _point_segment_dist2(qx, qy, ax, ay, bx, by)),
        min(_point_segment_dist2(ax, ay, px, py, qx, qy), _point_segment_dist2(bx, by, px, py, qx, qy)),
    )


@njit(cache=True)
def min_wall_distance(points: F8Array2, walls: F8Array2) -> F8Array1:
    """Distance (m) from each point (N, 2) to the nearest wall centre line; +inf if there are no walls."""
    out = np.full(points.shape[0], np.inf)
    for i in range(points.shape[0]):
        best = np.inf
        for j in range(walls.shape[0]):
            d2 = _point_segment_dist2(
                points[i, 0], points[i, 1], walls[j, 0], walls[j, 1], walls[j, 2], walls[j, 3]
            )
            if d2 < best:
                best = d2
        out[i] = math.sqrt(best)
    return out


@njit(cache=True)
def segment_blocked(
    px: float, py: float, qx: float, qy: float, walls: np.ndarray, wall_radius: float
) -> bool:
    """True if the segment pq passes within ``wall_radius`` of any wall, i.e. hits a wall capsule."""
    r2 = wall_radius * wall_radius
    for j in range(walls.shape[0]):
        if _segment_segment_dist2(px, py, qx, qy, walls[j, 0], walls[j, 1], walls[j, 2], walls[j, 3]) < r2:
            return True
    return False


@njit(cache=True)
def _walls_within(x: float, y: float, walls: np.ndarray, reach: float) -> np.ndarray:
    """Indices of the walls whose centre line comes within ``reach`` m of (x, y): the only ones a query of
    that length from (x, y) can touch, so the per-query loops skip the rest."""
    near = np.empty(walls.shape[0], dtype=np.int64)
    k = 0
    reach2 = reach * reach
    for j in range(walls.shape[0]):
        if _point_segment_dist2(x, y, walls[j, 0], walls[j, 1], walls[j, 2], walls[j, 3]) <= reach2:
            near[k] = j
            k += 1
    return near[:k]


@njit(cache=True)
def visible_landmarks(
    x: float,
    y: float,
    theta: float,
    landmarks: F8Array2,
    walls: F8Array2,
    wall_radius: float,
    min_range: float,
    max_range: float,
    half_fov: float,
    ids_out: I8Array1,
    z_out: F8Array2,
) -> int:
    """Noise-free readings of the landmarks a sensor at pose (x, y, theta) sees; returns their count m.

    Culls by range, then field of view, and only then tests the line of sight against the walls near enough
    to matter, so the expensive test runs on the few candidates left. Fills ``ids_out[:m]`` (ascending) and
    ``z_out[:m]`` with (range m, bearing rad in the sensor frame).
    """
    min2 = min_range * min_range
    max2 = max_range * max_range
    near = _walls_within(x, y, walls, max_range + wall_radius)
    r2 = wall_radius * wall_radius
    m = 0
    for i in range(landmarks.shape[0]):
        lx = landmarks[i, 0]
        ly = landmarks[i, 1]
        dx = lx - x
        dy = ly - y
        d2 = dx * dx + dy * dy
        if d2 < min2 or d2 > max2:
            continue
        bearing = wrap_angle(math.atan2(dy, dx) - theta)
        if abs(bearing) > half_fov:
            continue
        blocked = False
        for j in near:
            if _segment_segment_dist2(x, y, lx, ly, walls[j, 0], walls[j, 1], walls[j, 2], walls[j, 3]) < r2:
                blocked = True
                break
        if blocked:
            continue
        ids_out[m] = i
        z_out[m, 0] = math.sqrt(d2)
        z_out[m, 1] = bearing
        m += 1
    return m


@njit(cache=True)
def add_reading_noise(z: F8Array2, noise: F8Array2, range_std: float, bearing_std: float) -> None:
    """In place: z += (range_std, bearing_std) * noise, bearings re-wrapped to (-pi, pi]."""
    for i in range(z.shape[0]):
        z[i, 0] += range_std * noise[i, 0]
        z[i, 1] = wrap_angle(z[i, 1] + bearing_std * noise[i, 1])


@njit(cache=True)
def _ray_circle(ox: float, oy: float, dx: float, dy: float, cx: float, cy: float, r2: float) -> float:
    """Distance along the unit ray o + s d to the first point of the disc (c, r); inf if missed, 0 if inside."""
    fx = ox - cx
    fy = oy - cy
    c = fx * fx + fy * fy - r2
    if c <= 0.0:
        return 0.0
    b = fx * dx + fy * dy
    disc = b * b - c
    if disc < 0.0 or b > 0.0:
        return np.inf
    return -b - math.sqrt(disc)


@njit(cache=True)
def _ray_capsule(
    ox: float, oy: float, dx: float, dy: float, ax: float, ay: float, bx: float, by: float, r: float
) -> float:
    """Distance along the unit ray o + s d to the capsule (segment ab swept by r); inf if missed."""
    best = min(_ray_circle(ox, oy, dx, dy, ax, ay, r * r), _ray_circle(ox, oy, dx, dy, bx, by, r * r))
    ex = bx - ax
    ey = by - ay
    length = math.sqrt(ex * ex + ey * ey)
    if length == 0.0:
        return best
    ux = ex / length
    uy = ey / length
    # the two long sides: lines at signed offset +-r along the normal (-uy, ux)
    o_n = (ox - ax) * -uy + (oy - ay) * ux
    d_n = dx * -uy + dy * ux
    o_t = (ox - ax) * ux + (oy - ay) * uy
    d_t = dx * ux + dy * uy
    if abs(o_n) <= r and 0.0 <= o_t <= length:
        return 0.0
    if d_n != 0.0:
        for side in (-r, r):
            s = (side - o_n) / d_n
            if 0.0 <= s < best:
                t = o_t + s * d_t
                if 0.0 <= t <= length:
                    best = s
    return best


@njit(cache=True)
def cast_rays(
    x: float,
    y: float,
    theta: float,
    beam_angles: F8Array1,
    walls: F8Array2,
    wall_radius: float,
    max_range: float,
    out: F8Array1,
) -> None:
    """Distance (m) from (x, y) along each beam (angle rad relative to theta) to the first wall surface.

    Writes ``out[i]``, clipped at ``max_range``.
    """
    near = _walls_within(x, y, walls, max_range + wall_radius)
    for i in range(beam_angles.shape[0]):
        a = theta + beam_angles[i]
        dx = math.cos(a)
        dy = math.sin(a)
        best = max_range
        for j in near:
            s = _ray_capsule(x, y, dx, dy, walls[j, 0], walls[j, 1], walls[j, 2], walls[j, 3], wall_radius)
            if s < best:
                best = s
        out[i] = best


@njit(cache=True)
def accept_spaced(candidates: F8Array2, accepted: F8Array2, count: int, spacing2: float) -> int:
    """Greedily append candidates at least sqrt(spacing2) m from every accepted point, in order, until
    ``accepted`` is full; returns the new count."""
    for i in range(candidates.shape[0]):
        if count == accepted.shape[0]:
            break
        ok = True
        for j in range(count):
            dx = accepted[j, 0] - candidates[i, 0]
            dy = accepted[j, 1] - candidates[i, 1]
            if dx * dx + dy * dy < spacing2:
                ok = False
                break
        if ok:
            accepted[count, 0] = candidates[i, 0]
            accepted[count, 1] = candidates[i, 1]
            count += 1
    return count


@njit(cache=True)
def connected_component(free: BoolArray2, row: int, col: int) -> BoolArray2:
    """The cells of the boolean grid ``free`` 4-connected to (row, col) (which must be free), by flood fill."""
    rows, cols = free.shape
    component = np.zeros((rows, cols), dtype=np.bool_)
    stack = np.empty((rows * cols, 2), dtype=np.int64)
    stack[0, 0] = row
    stack[0, 1] = col
    component[row, col] = True
    top = 1
    while top > 0:
        top -= 1
        r = stack[top, 0]
        c = stack[top, 1]
        for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            nr = r + dr
            nc = c + dc
            if 0 <= nr < rows and 0 <= nc < cols and free[nr, nc] and not component[nr, nc]:
                component[nr, nc] = True
                stack[top, 0] = nr
                stack[top, 1] = nc
                top += 1
    return component


@njit(cache=True)
def free_cells(
    walls: F8Array2, x0: float, y0: float, cell: float, rows: int, cols: int, clearance: float
) -> BoolArray2:
    """The grid (rows, cols) of cells whose centres (x0 + (col + 0.5) cell, y0 + (row + 0.5) cell) lie at least
    ``clearance`` m from every wall centre line: ``min_wall_distance(centres, walls) >= clearance``, cell for
    cell, but visiting only the cells near each wall (a layout's free-space grid in ~0.1 ms, not ~50 ms)."""
    free = np.ones((rows, cols), dtype=np.bool_)
    for j in range(walls.shape[0]):
        ax = walls[j, 0]
        ay = walls[j, 1]
        bx = walls[j, 2]
        by = walls[j, 3]
        # every centre within ``clearance`` of the segment lies in its bounding box grown by ``clearance``
        c0 = max(0, int(math.floor((min(ax, bx) - clearance - x0) / cell - 0.5)) - 1)
        c1 = min(cols - 1, int(math.ceil((max(ax, bx) + clearance - x0) / cell - 0.5)) + 1)
        r0 = max(0, int(math.floor((min(ay, by) - clearance - y0) / cell - 0.5)) - 1)
        r1 = min(rows - 1, int(math.ceil((max(ay, by) + clearance - y0) / cell - 0.5)) + 1)
        for r in range(r0, r1 + 1):
            py = y0 + (r + 0.5) * cell
            for c in range(c0, c1 + 1):
                if free[r, c]:
                    px = x0 + (c + 0.5) * cell
                    if math.sqrt(_point_segment_dist2(px, py, ax, ay, bx, by)) < clearance:
                        free[r, c] = False
    return free
