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
coverage   G*G    a robot-centred window, turned with the estimated heading and reaching grid_extent m each
                  side, of the coverage memory: 1 where the sensor has looked (a memory cell whose centre was
                  within range and field of view of the pose *estimate* at some step; walls ignored, the
                  belief has none) or outside the world, else 0. Row-major: row 0 is furthest to the left,
                  column 0 furthest behind, so the robot faces along the rows towards the last column
coverage_  C*C    the same, coarser and wider (coarse_grid cells reaching coarse_extent m): each cell the
coarse            fraction of it looked at, so that beyond the fine window the robot still knows where the
                  unexplored part of the world lies (0 disables it)
========== ====== ================================================================================================

Everything is computed by one compiled kernel writing into a preallocated vector: the env is stepped millions
of times and each numpy call costs microseconds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..filter.kernels import det3

CLIP = 5.0
LANDMARK_FEATURES = 4
COARSE_SAMPLES = 4  # points per side averaged in each cell of the coarse window


def observation_layout(k_nearest: int, n_beams: int, grid: int, coarse_grid: int = 0) -> dict[str, slice]:
    """Name -> slice of the flat observation vector."""
    sizes = {
        "pose": 4,
        "pose_cov": 3,
        "landmarks": LANDMARK_FEATURES * k_nearest,
        "globals": 3,
        "scan": n_beams,
        "coverage": grid * grid,
    }
    if coarse_grid:
        sizes["coverage_coarse"] = coarse_grid * coarse_grid
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


def make_memory(bounds: np.ndarray, resolution: float) -> np.ndarray:
    """An empty coverage memory over the world's bounds, ``resolution`` m per cell, rows along y."""
    cols = max(1, int(math.ceil((bounds[2] - bounds[0]) / resolution)))
    rows = max(1, int(math.ceil((bounds[3] - bounds[1]) / resolution)))
    return np.zeros((rows, cols))


@njit(cache=True)
def mark_coverage(memory, pose, bounds, resolution, max_range, fov):
    """Set the memory cells whose centres lie within max_range and the field of view of ``pose``.

    Walls are ignored: the belief holds none, so the memory records where the sensor pointed, not what it saw.
    Only the footprint's bounding box is visited. Returns how many cells were newly marked.
    """
    rows, cols = memory.shape
    half_fov = 0.5 * fov
    c0 = max(0, int((pose[0] - max_range - bounds[0]) / resolution))
    c1 = min(cols - 1, int((pose[0] + max_range - bounds[0]) / resolution))
    r0 = max(0, int((pose[1] - max_range - bounds[1]) / resolution))
    r1 = min(rows - 1, int((pose[1] + max_range - bounds[1]) / resolution))
    range2 = max_range * max_range
    marked = 0
    for row in range(r0, r1 + 1):
        dy = bounds[1] + (row + 0.5) * resolution - pose[1]
        for col in range(c0, c1 + 1):
            if memory[row, col]:
                continue
            dx = bounds[0] + (col + 0.5) * resolution - pose[0]
            if dx * dx + dy * dy > range2:
                continue
            bearing = (math.atan2(dy, dx) - pose[2] + math.pi) % (2.0 * math.pi) - math.pi
            if abs(bearing) <= half_fov:
                memory[row, col] = 1.0
                marked += 1
    return marked


@njit(cache=True)
def _window(out, o, memory, bounds, resolution, x, y, c, s, grid, extent, samples):
    """Write a robot-centred grid x grid window of the coverage memory at out[o:], reaching ``extent`` m to
    each side; each cell is the mean of samples x samples points in it. Returns the next offset.

    Cell (row, col) sits at (forward, left) offsets in the robot frame: row 0 furthest to the left, column 0
    furthest behind. Outside the world counts as looked at (there is nothing to find there).
    """
    rows, cols = memory.shape
    cell = 2.0 * extent / grid
    step = cell / samples
    for row in range(grid):
        for col in range(grid):
            total = 0.0
            for i in range(samples):
                left = extent - row * cell - (i + 0.5) * step
                for j in range(samples):
                    forward = -extent + col * cell + (j + 0.5) * step
                    wx = x + c * forward - s * left
                    wy = y + s * forward + c * left
                    mc = int(math.floor((wx - bounds[0]) / resolution))
                    mr = int(math.floor((wy - bounds[1]) / resolution))
                    if 0 <= mr < rows and 0 <= mc < cols:
                        total += memory[mr, mc]
                    else:
                        total += 1.0
            out[o + row * grid + col] = total / (samples * samples)
    return o + grid * grid


@njit(cache=True)
def fill_observation(
    out,
    mean,
    cov,
    observed,
    log_det,
    pose_given_map,
    scan,
    memory,
    bounds,
    resolution,
    grid,
    extent,
    coarse_grid,
    coarse_extent,
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
    o = _window(out, o, memory, bounds, resolution, x, y, c, s, grid, extent, 1)
    if coarse_grid > 0:
        _window(out, o, memory, bounds, resolution, x, y, c, s, coarse_grid, coarse_extent, COARSE_SAMPLES)
