"""The waypoint controller's clearance geometry, compiled: how far the robot's disc can drive straight ahead (or
back) before it touches a wall that the scan shows.

Compiled because the controller asks at every control step of the ``waypoint`` action kind, of the primitives'
``guard`` and of the frontier planners that teach the learned policies, and in Python the loop over the beams
cost ~35 us a call. Delivered through ``ekfslam_gym.compiled`` (ahead of time when installed, else numba's JIT);
``ekfslam_gym.envs.waypoint`` wraps them. The walls are the hit end points and the segments joining neighbouring
hit end points less than ``join`` m apart (one surface seen by two beams).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..kernel_types import BoolArray1, F8Array1


@njit(cache=True)
def _point_travel(x: float, y: float, rho: float) -> float:
    """How far a disc of radius ``rho`` at the origin moves along +x before touching the point (x, y): inf if it
    passes by or the point is behind, 0 if the disc already overlaps a point in front of its centre."""
    if abs(y) >= rho:
        return math.inf
    s = x - math.sqrt(rho * rho - y * y)
    if s >= 0.0:
        return s
    return 0.0 if x > 0.0 else math.inf


@njit(cache=True)
def _segment_travel(ax: float, ay: float, bx: float, by: float, rho: float) -> float:
    """How far a disc of radius ``rho`` at the origin moves along +x before touching the *inside* of segment
    AB (its end points are points of their own, see ``_point_travel``): the ray against the capsule's two
    sides. Overlapping already: 0 if the nearest point of the segment lies in front of the centre, else inf
    (moving on takes the disc away)."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    if length2 <= 0.0:
        return math.inf
    t = min(max(-(ax * dx + ay * dy) / length2, 0.0), 1.0)
    cx, cy = ax + t * dx, ay + t * dy
    if cx * cx + cy * cy < rho * rho:
        return 0.0 if cx > 0.0 else math.inf
    length = math.sqrt(length2)
    nx, ny = -dy / length * rho, dx / length * rho
    best = math.inf
    for side in range(2):
        sign = 1.0 if side == 0 else -1.0
        py, qy = ay + sign * ny, by + sign * ny
        if (py > 0.0) == (qy > 0.0):
            continue  # this side does not cross the line of travel
        px, qx = ax + sign * nx, bx + sign * nx
        s = px + py / (py - qy) * (qx - px)
        if 0.0 <= s < best:
            best = s
    return best


@njit(cache=True)
def travel_distance(xs: F8Array1, ys: F8Array1, hit: BoolArray1, rho: float, join: float) -> float:
    """How far (m) a disc of radius ``rho`` at the origin can move along +x before it touches a wall.

    ``xs``, ``ys``: the scan's end points (float64) in a frame whose x axis is the direction of travel, beam by
    beam around the circle; ``hit``: which beams ended on a wall. 0 when a wall in front already overlaps the
    disc; inf when nothing lies in the way.
    """
    n = xs.shape[0]
    best = math.inf
    rho2 = rho * rho
    join2 = join * join
    for i in range(n):
        if not hit[i]:
            continue
        x, y = xs[i], ys[i]
        if x > -rho and abs(y) < rho:
            s = _point_travel(x, y, rho)
            if s < best:
                best = s
        k = i + 1 if i + 1 < n else 0
        if k == i or not hit[k]:
            continue
        bx, by = xs[k], ys[k]
        if (x - bx) ** 2 + (y - by) ** 2 >= join2:
            continue
        if (
            (y >= rho and by >= rho)
            or (y <= -rho and by <= -rho)
            or (x < 0.0 and bx < 0.0 and x * x + y * y >= rho2 and bx * bx + by * by >= rho2)
        ):
            continue  # wholly to one side of the swept band, or behind and clear
        s = _segment_travel(x, y, bx, by, rho)
        if s < best:
            best = s
    return best


@njit(cache=True)
def scan_clearances(
    ranges: F8Array1, cos: F8Array1, sin: F8Array1, limit: float, rho: float, join: float, behind_too: bool
) -> tuple[float, float, float]:
    """(room ahead, room behind, nearest hit range) in m for a scan of ``ranges`` along unit directions (``cos``,
    ``sin``) in the robot's frame; a beam hit a wall when its range is below ``limit``. With ``behind_too``
    False only the room ahead is measured (the others are inf)."""
    n = ranges.shape[0]
    xs = np.empty(n)
    ys = np.empty(n)
    hit = np.empty(n, dtype=np.bool_)
    nearest = math.inf
    for i in range(n):
        r = ranges[i]
        xs[i] = r * cos[i]
        ys[i] = r * sin[i]
        hit[i] = r < limit
        if hit[i] and r < nearest:
            nearest = r
    ahead = travel_distance(xs, ys, hit, rho, join)
    if not behind_too:
        return ahead, math.inf, math.inf
    for i in range(n):
        xs[i] = -xs[i]
    return ahead, travel_distance(xs, ys, hit, rho, join), nearest
