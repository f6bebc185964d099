"""Compiled kernels of the team env's hot path (numba, ``cache=True``): the geometry robots add to the
simulator (a disc on a line of sight, a beam stopped by a disc) and the teammate part of the observation.

Each is a plain loop over a handful of robots and readings; as numpy calls they cost several microseconds of
overhead each, at every control step, for every robot.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def segments_blocked(sx, sy, ends, centres, radius):
    """Whether the segment from (sx, sy) to each of ``ends`` (m, 2) passes within ``radius`` of any of
    ``centres`` (k, 2) (bool (m,)); a centre at the segment's end does not count."""
    m = ends.shape[0]
    out = np.zeros(m, dtype=np.bool_)
    r2 = radius * radius
    for a in range(m):
        dx = ends[a, 0] - sx
        dy = ends[a, 1] - sy
        length2 = max(dx * dx + dy * dy, 1e-12)
        for b in range(centres.shape[0]):
            cx, cy = centres[b, 0], centres[b, 1]
            ex, ey = ends[a, 0] - cx, ends[a, 1] - cy
            if ex * ex + ey * ey < 1e-12:
                continue
            t = ((cx - sx) * dx + (cy - sy) * dy) / length2
            t = min(max(t, 0.0), 1.0)
            gx = sx + t * dx - cx
            gy = sy + t * dy - cy
            if gx * gx + gy * gy < r2:
                out[a] = True
                break
    return out


@njit(cache=True)
def stop_beams_at_discs(x, y, theta, angles, centres, radius, out):
    """In place: each beam's distance ``out[i]`` (heading + ``angles[i]`` from (x, y)) cut at the first point of
    any disc of ``radius`` at ``centres`` (k, 2); 0 for a beam starting inside one."""
    r2 = radius * radius
    for i in range(angles.shape[0]):
        dx = math.cos(theta + angles[i])
        dy = math.sin(theta + angles[i])
        for b in range(centres.shape[0]):
            fx = x - centres[b, 0]
            fy = y - centres[b, 1]
            c = fx * fx + fy * fy - r2
            if c <= 0.0:
                out[i] = 0.0
                continue
            h = fx * dx + fy * dy
            disc = h * h - c
            if disc < 0.0:
                continue
            s = -h - math.sqrt(disc)
            if 0.0 <= s < out[i]:
                out[i] = s


@njit(cache=True)
def fill_teammates(out, robot, mean, cov, n_robots, half_size, clip, features):
    """Robot ``robot``'s teammate slots (``features`` per slot, ``ekfslam_gym.multi.observation``'s table) from
    the joint belief (mean, cov), robots' poses at 3r..3r+2, nearest estimate first; zeros beyond them."""
    out[:] = 0.0
    slots = out.shape[0] // features
    if slots == 0 or n_robots == 1:
        return
    i = 3 * robot
    x, y, theta = mean[i], mean[i + 1], mean[i + 2]
    c, s = math.cos(theta), math.sin(theta)
    distances = np.empty(n_robots)
    for r in range(n_robots):
        dx = mean[3 * r] - x
        dy = mean[3 * r + 1] - y
        distances[r] = math.inf if r == robot else dx * dx + dy * dy
    for slot in range(min(slots, n_robots - 1)):
        r = np.argmin(distances)  # the nearest not yet placed (stable: the lower index first on ties)
        distances[r] = math.inf
        j = 3 * r
        dx, dy = mean[j] - x, mean[j + 1] - y
        xx = cov[j, j] + cov[i, i] - 2.0 * cov[j, i]
        yy = cov[j + 1, j + 1] + cov[i + 1, i + 1] - 2.0 * cov[j + 1, i + 1]
        turn = mean[j + 2] - theta
        o = features * slot
        values = (
            1.0,
            (c * dx + s * dy) / half_size,
            (-s * dx + c * dy) / half_size,
            math.sin(turn),
            math.cos(turn),
            math.log(max(0.5 * (xx + yy), 1e-300)) / 10.0,
        )
        for f in range(features):
            out[o + f] = min(max(values[f], -clip), clip)


@njit(cache=True)
def worst_landmark_variance(cov, first):
    """The largest eigenvalue of any landmark's 2 x 2 marginal covariance (landmarks from column ``first``),
    m^2; 0 with none."""
    worst = 0.0
    for k in range(first, cov.shape[0] - 1, 2):
        a, b, c = cov[k, k], cov[k, k + 1], cov[k + 1, k + 1]
        half = 0.5 * (a - c)
        value = 0.5 * (a + c) + math.sqrt(half * half + b * b)
        if value > worst:
            worst = value
    return worst


@njit(cache=True)
def pose_nees(true_pose, mean, cov, first):
    """The NEES (3 dof) of the pose at ``mean[first:first + 3]`` against ``true_pose`` (x, y, theta; the heading
    error wrapped to (-pi, pi]), with its block of ``cov``; NaN if that block is singular."""
    e = np.empty(3)
    for k in range(3):
        e[k] = true_pose[k] - mean[first + k]
    e[2] = math.atan2(math.sin(e[2]), math.cos(e[2]))
    block = cov[first : first + 3, first : first + 3].copy()
    try:
        return float(e @ np.linalg.solve(block, e))
    except Exception:  # noqa: BLE001 (numba raises a plain exception for a singular matrix)
        return math.nan


@njit(cache=True)
def map_rmse(mean, first, observed, truth):
    """RMS position error (m) of the observed landmarks' estimates (from ``mean[first]`` on) against ``truth``
    (n, 2); NaN with none observed."""
    total = 0.0
    count = 0
    for j in range(observed.shape[0]):
        if observed[j]:
            dx = mean[first + 2 * j] - truth[j, 0]
            dy = mean[first + 2 * j + 1] - truth[j, 1]
            total += dx * dx + dy * dy
            count += 1
    return math.sqrt(total / count) if count else math.nan
