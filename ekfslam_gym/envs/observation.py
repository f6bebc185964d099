"""The observation: the filter's belief, the wall scan and a coverage memory, as one normalised float32 vector.

Layout of the flat vector (``observation_layout`` gives the slices; the Dict variant uses the same names):

========== ====== ================================================================================================
part       size   contents (all clipped to [-CLIP, CLIP])
========== ====== ================================================================================================
pose       4      estimated (x, y) relative to the world's centre / half its larger side; sin and cos of heading
pose_cov   3      ln of the pose variances (x, y, theta) / 10
landmarks  4 k    the k seen landmarks nearest the pose estimate, nearest first: [seen flag, x and y of the
                  estimate in the robot's frame / sensor max_range, ln(trace of its 2x2 covariance / 2) / 10];
                  slots beyond the seen landmarks are all zero
globals    3      mean ln variance of the map (ln det Sigma_mm / 2n / 10), fraction of landmarks seen, time left
scan       B      wall distances along B beams fixed to the robot / scan_max_range (1 = nothing within range)
coverage   G*G    1 where the sensor has looked (cell centre within range and field of view of the pose
                  *estimate* at some step; walls ignored, the belief has none), row-major from (xmin, ymin)
========== ====== ================================================================================================

Everything is computed by one compiled kernel writing into a preallocated vector: the env is stepped millions
of times and each numpy call costs microseconds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..slam._kernels import det3

CLIP = 5.0
LANDMARK_FEATURES = 4


def observation_layout(k_nearest: int, n_beams: int, grid: int) -> dict[str, slice]:
    """Name -> slice of the flat observation vector."""
    sizes = {
        "pose": 4,
        "pose_cov": 3,
        "landmarks": LANDMARK_FEATURES * k_nearest,
        "globals": 3,
        "scan": n_beams,
        "coverage": grid * grid,
    }
    layout, start = {}, 0
    for name, size in sizes.items():
        layout[name] = slice(start, start + size)
        start += size
    return layout


@njit(cache=True)
def _clip(value: float) -> float:
    if value > CLIP:
        return CLIP
    if value < -CLIP:
        return -CLIP
    return value


@njit(cache=True)
def mark_coverage(coverage, pose, bounds, max_range, fov):
    """Set the coverage cells whose centres lie within max_range and the field of view of ``pose``."""
    grid = coverage.shape[0]
    cell_w = (bounds[2] - bounds[0]) / grid
    cell_h = (bounds[3] - bounds[1]) / grid
    half_fov = 0.5 * fov
    for row in range(grid):
        cy = bounds[1] + (row + 0.5) * cell_h
        for col in range(grid):
            if coverage[row, col]:
                continue
            cx = bounds[0] + (col + 0.5) * cell_w
            dx = cx - pose[0]
            dy = cy - pose[1]
            if dx * dx + dy * dy > max_range * max_range:
                continue
            bearing = math.atan2(dy, dx) - pose[2]
            bearing = (bearing + math.pi) % (2.0 * math.pi) - math.pi
            if abs(bearing) <= half_fov:
                coverage[row, col] = 1.0


@njit(cache=True)
def fill_observation(
    out,
    mean,
    cov,
    observed,
    log_det,
    pose_given_map,
    scan,
    coverage,
    centre,
    half_size,
    max_range,
    scan_max,
    time_left,
    k,
):
    """Write the flat observation (see the module docstring) into ``out`` (float32).

    ``log_det`` is log det Sigma and ``pose_given_map`` is P, so log det Sigma_mm = log det Sigma - log det P.
    """
    x, y, theta = mean[0], mean[1], mean[2]
    c, s = math.cos(theta), math.sin(theta)
    out[0] = _clip((x - centre[0]) / half_size)
    out[1] = _clip((y - centre[1]) / half_size)
    out[2] = s
    out[3] = c
    for i in range(3):
        out[4 + i] = _clip(math.log(max(cov[i, i], 1e-300)) / 10.0)

    n = observed.shape[0]
    distances = np.empty(n)
    n_seen = 0
    for j in range(n):
        if observed[j]:
            dx = mean[3 + 2 * j] - x
            dy = mean[4 + 2 * j] - y
            distances[j] = dx * dx + dy * dy
            n_seen += 1
        else:
            distances[j] = np.inf
    order = np.argsort(distances)
    base = 7
    for slot in range(k):
        o = base + LANDMARK_FEATURES * slot
        if slot < n_seen:
            j = order[slot]
            dx = mean[3 + 2 * j] - x
            dy = mean[4 + 2 * j] - y
            lj = 3 + 2 * j
            half_trace = 0.5 * (cov[lj, lj] + cov[lj + 1, lj + 1])
            out[o] = 1.0
            out[o + 1] = _clip((c * dx + s * dy) / max_range)
            out[o + 2] = _clip((-s * dx + c * dy) / max_range)
            out[o + 3] = _clip(math.log(max(half_trace, 1e-300)) / 10.0)
        else:
            for f in range(LANDMARK_FEATURES):
                out[o + f] = 0.0

    o = base + LANDMARK_FEATURES * k
    log_det_map = log_det - math.log(det3(pose_given_map)) if n else 0.0
    out[o] = _clip(log_det_map / max(2 * n, 1) / 10.0)
    out[o + 1] = n_seen / max(n, 1)
    out[o + 2] = time_left
    o += 3
    for b in range(scan.shape[0]):
        out[o + b] = min(scan[b] / scan_max, 1.0)
    o += scan.shape[0]
    grid = coverage.shape[0]
    for row in range(grid):
        for col in range(grid):
            out[o + row * grid + col] = coverage[row, col]
