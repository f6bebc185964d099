"""The env's compiled kernels: the observation (one call writes the whole flat vector), the coverage memory, the
belief image and its wall memory (``observation.belief_image``), and the per-step metrics. Compiled because the
env is stepped millions of times and each numpy call costs microseconds; delivered through
``ekfslam_gym.compiled`` (ahead of time when installed, else numba's JIT).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..angles import compiled_wrap_angle as wrap_angle
from ..filter.kernels import det3
from ..kernel_types import BoolArray1, F4Array1, F8Array1, F8Array2, I8Array1
from .observation_codes import (
    BELIEF_COVERAGE,
    BELIEF_LANDMARKS,
    BELIEF_WALLS,
    CLIP,
    COARSE_EXTENT,
    COARSE_SAMPLES,
    COVERAGE,
    COVERAGE_COARSE,
    GLOBALS,
    GRID_EXTENT,
    LANDMARK_FEATURES,
    LANDMARKS,
    MAX_RANGE,
    MEMORY_RESOLUTION,
    POSE,
    POSE_COV,
    SCAN,
    SCAN_MAX_RANGE,
)


@njit(cache=True)
def _clip(value: float) -> float:
    if value > CLIP:
        return CLIP
    if value < -CLIP:
        return -CLIP
    return value


@njit(cache=True)
def mark_coverage(
    memory: F8Array2, pose: F8Array1, bounds: F8Array1, resolution: float, max_range: float, fov: float
) -> int:
    """Set the memory cells whose centres lie within max_range and the field of view of ``pose``.

    Walls are ignored: the belief holds none, so the memory records where the sensor pointed, not what it saw.
    Only the footprint's bounding box is visited. Returns how many cells were newly marked.

    A cell whose direction is plainly outside the field of view (its cosine with the heading below
    cos(fov / 2) by far more than rounding) is passed over without the exact bearing: with the default
    half-circle view, half of every footprint is behind the robot and would cost an arctangent each step.
    """
    rows, cols = memory.shape
    half_fov = 0.5 * fov
    heading_c, heading_s = math.cos(pose[2]), math.sin(pose[2])
    cos_limit = math.cos(half_fov) - 1e-6
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
            distance2 = dx * dx + dy * dy
            if distance2 > range2:
                continue
            if heading_c * dx + heading_s * dy < cos_limit * math.sqrt(distance2):
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
    # A multiplication instead of two divisions per sample (481 samples a step by default): exactly the same
    # cells when the resolution is a power of two (the default 0.5 m), else the same up to rounding.
    per_metre = 1.0 / resolution
    for row in range(grid):
        for col in range(grid):
            total = 0.0
            for i in range(samples):
                left = extent - row * cell - (i + 0.5) * step
                for j in range(samples):
                    forward = -extent + col * cell + (j + 0.5) * step
                    wx = x + c * forward - s * left
                    wy = y + s * forward + c * left
                    # Truncation is the floor on the non-negative side; the negative side lies outside.
                    fc = (wx - bounds[0]) * per_metre
                    fr = (wy - bounds[1]) * per_metre
                    if 0.0 <= fr < rows and 0.0 <= fc < cols:
                        total += memory[int(fr), int(fc)]
                    else:
                        total += 1.0
            out[o + row * grid + col] = total / (samples * samples)
    return o + grid * grid


@njit(cache=True)
def _window_side(offsets, part):
    """Side of the square window stored as part ``part`` (0 when absent)."""
    return int(math.sqrt(offsets[part + 1] - offsets[part]) + 0.5)


@njit(cache=True)
def fill_observation(
    out: F4Array1,
    offsets: I8Array1,
    constants: F8Array1,
    mean: F8Array1,
    cov: F8Array2,
    observed: BoolArray1,
    log_det: float,
    pose_given_map: F8Array2,
    scan: F8Array1,
    memory: F8Array2,
    bounds: F8Array1,
    time_left: float,
) -> None:
    """Write the flat observation (see the module docstring) into ``out`` (float32).

    ``offsets`` is ``ObservationLayout.offsets`` (where each part goes), ``constants`` is
    ``observation_constants(...)``; ``bounds`` (xmin, ymin, xmax, ymax) of the world hold the memory.
    ``log_det`` is log det Sigma and ``pose_given_map`` is P, so log det Sigma_mm = log det Sigma - log det P.
    """
    max_range = constants[MAX_RANGE]
    resolution = constants[MEMORY_RESOLUTION]
    centre_x = 0.5 * (bounds[0] + bounds[2])
    centre_y = 0.5 * (bounds[1] + bounds[3])
    half_size = 0.5 * max(bounds[2] - bounds[0], bounds[3] - bounds[1])
    x, y, theta = mean[0], mean[1], mean[2]
    c, s = math.cos(theta), math.sin(theta)
    o = offsets[POSE]
    out[o] = _clip((x - centre_x) / half_size)
    out[o + 1] = _clip((y - centre_y) / half_size)
    out[o + 2] = s
    out[o + 3] = c
    o = offsets[POSE_COV]
    for i in range(3):
        out[o + i] = _clip(math.log(max(cov[i, i], 1e-300)) / 10.0)

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
    base = offsets[LANDMARKS]
    k = (offsets[LANDMARKS + 1] - base) // LANDMARK_FEATURES
    for slot in range(k):
        o = base + LANDMARK_FEATURES * slot
        if slot < n_seen:
            j = np.argmin(distances)  # the nearest not yet placed: k passes instead of sorting all n
            distances[j] = np.inf
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

    o = offsets[GLOBALS]
    log_det_map = log_det - math.log(det3(pose_given_map)) if n else 0.0
    out[o] = _clip(log_det_map / max(2 * n, 1) / 10.0)
    out[o + 1] = n_seen / max(n, 1)
    out[o + 2] = time_left
    o = offsets[SCAN]
    scan_max = constants[SCAN_MAX_RANGE]
    for b in range(offsets[SCAN + 1] - o):
        out[o + b] = min(scan[b] / scan_max, 1.0)
    grid = _window_side(offsets, COVERAGE)
    _window(out, offsets[COVERAGE], memory, bounds, resolution, x, y, c, s, grid, constants[GRID_EXTENT], 1)
    coarse_grid = _window_side(offsets, COVERAGE_COARSE)
    if coarse_grid > 0:
        _window(
            out, offsets[COVERAGE_COARSE], memory, bounds, resolution, x, y, c, s, coarse_grid,
            constants[COARSE_EXTENT], COARSE_SAMPLES,
        )  # fmt: skip


@njit(cache=True)
def mark_walls(
    walls: F8Array2,
    pose: F8Array1,
    bounds: F8Array1,
    resolution: float,
    scan: F8Array1,
    beam_angles: F8Array1,
    scan_max_range: float,
) -> int:
    """Set the wall-memory cells holding the endpoints of the scan's beams that hit a wall (a distance below
    ``scan_max_range``), each endpoint placed from ``pose``, the pose *estimate*: the memory is the belief's
    picture of the walls, drawn where the robot believes it stands. Returns how many cells were newly marked.

    ``walls`` is laid out like the coverage memory (rows along y from ``bounds``' corner, ``resolution`` m per
    cell); beam i points at heading + ``beam_angles[i]``, as the sensor casts it. Endpoints outside the world
    are dropped.
    """
    rows, cols = walls.shape
    per_metre = 1.0 / resolution  # as ``_window`` reads the memory, so a cell is marked where it is read
    marked = 0
    for i in range(scan.shape[0]):
        distance = scan[i]
        if not distance < scan_max_range:
            continue
        angle = pose[2] + beam_angles[i]
        fc = (pose[0] + distance * math.cos(angle) - bounds[0]) * per_metre
        fr = (pose[1] + distance * math.sin(angle) - bounds[1]) * per_metre
        if 0.0 <= fr < rows and 0.0 <= fc < cols:
            row, col = int(fr), int(fc)
            if walls[row, col] == 0.0:
                walls[row, col] = 1.0
                marked += 1
    return marked


@njit(cache=True)
def _belief_windows(out, size, coverage, walls, bounds, resolution, x, y, c, s, extent, samples):
    """The coverage and wall channels in one pass over the sample points (each point read in both memories):
    a coverage cell is the mean of its samples x samples points, as ``_window``'s, a wall cell the largest (a wall
    a sample wide still reads 1); outside the world both read 1. Same cell layout as ``_window``."""
    rows, cols = coverage.shape
    cell = 2.0 * extent / size
    step = cell / samples
    per_metre = 1.0 / resolution
    o_coverage = BELIEF_COVERAGE * size * size
    o_walls = BELIEF_WALLS * size * size
    for row in range(size):
        for col in range(size):
            total = 0.0
            largest = 0.0
            for i in range(samples):
                left = extent - row * cell - (i + 0.5) * step
                for j in range(samples):
                    forward = -extent + col * cell + (j + 0.5) * step
                    fc = (x + c * forward - s * left - bounds[0]) * per_metre
                    fr = (y + s * forward + c * left - bounds[1]) * per_metre
                    if 0.0 <= fr < rows and 0.0 <= fc < cols:
                        r, k = int(fr), int(fc)
                        total += coverage[r, k]
                        if walls[r, k] > largest:
                            largest = walls[r, k]
                    else:
                        total += 1.0
                        largest = 1.0
            out[o_coverage + row * size + col] = total / (samples * samples)
            out[o_walls + row * size + col] = largest


@njit(cache=True)
def fill_belief_image(
    out: F4Array1,
    size: int,
    coverage: F8Array2,
    walls: F8Array2,
    bounds: F8Array1,
    mean: F8Array1,
    cov: F8Array2,
    observed: BoolArray1,
    resolution: float,
    extent: float,
) -> None:
    """Write the belief image, (3, size, size) float32 flattened C-order into ``out``, from the belief alone.

    The window is centred on the pose estimate mean[:3] and turned with its heading, reaching ``extent`` m to
    each side, the cells laid out as ``_window``'s (row 0 furthest to the left, column 0 furthest behind).
    Channel ``BELIEF_COVERAGE``: the coverage memory, each cell the mean of samples x samples points in it
    (samples = ceil(cell / resolution), so every memory cell under it counts); ``BELIEF_WALLS``: the wall memory
    of ``mark_walls``, each cell the largest of its points (a wall is thin); both 1 outside the world
    (``_belief_windows``, one pass for both).
    ``BELIEF_LANDMARKS``: each seen landmark's estimate in the cell that holds it, valued by its certainty
    1 / (1 + sqrt(tr Sigma_jj) / cell): 1/2 when the expected position error (the root of the trace of the
    marginal 2x2 covariance, Thrun, Burgard & Fox ch. 3) is one cell, near 1 when far below it; the largest
    where several share a cell. Nothing here reads the true pose, map or walls.
    """
    x, y, theta = mean[0], mean[1], mean[2]
    c, s = math.cos(theta), math.sin(theta)
    cell = 2.0 * extent / size
    samples = max(1, int(math.ceil(cell / resolution - 1e-9)))
    area = size * size
    _belief_windows(out, size, coverage, walls, bounds, resolution, x, y, c, s, extent, samples)
    o = BELIEF_LANDMARKS * area
    for i in range(area):
        out[o + i] = 0.0
    for j in range(observed.shape[0]):
        if not observed[j]:
            continue
        lj = 3 + 2 * j
        dx = mean[lj] - x
        dy = mean[lj + 1] - y
        row = math.floor((extent - (-s * dx + c * dy)) / cell)
        col = math.floor((c * dx + s * dy + extent) / cell)
        if 0 <= row < size and 0 <= col < size:
            certainty = 1.0 / (1.0 + math.sqrt(max(cov[lj, lj] + cov[lj + 1, lj + 1], 0.0)) / cell)
            k = o + int(row) * size + int(col)
            if certainty > out[k]:
                out[k] = certainty


@njit(cache=True)
def step_metrics(
    mean: F8Array1,
    cov: F8Array2,
    observed: BoolArray1,
    true_pose: tuple[float, float, float],
    true_landmarks: F8Array2,
    read_ids: I8Array1,
    last_seen: I8Array1,
    errors: F8Array1,
    traces: F8Array1,
    t: int,
    loop_gap: int,
) -> tuple[float, float, int, float, int, float, float]:
    """Pose NEES, map RMSE of seen landmarks, new loop closures, largest landmark marginal variance, the
    number of landmarks seen, the truth gain and the belief gain.

    ``true_pose`` is (x, y, theta), theta unwrapped. Also stamps ``last_seen`` for the landmarks read at step
    t. One compiled call instead of a dozen numpy ones.

    The truth gain (m^2) is the drop of the squared position errors of the landmarks seen both at the last
    call and now: sum of errors[j] - e_j over those, e_j = |estimate_j - true_j|^2. ``errors`` (n,) holds
    each landmark's e_j of the last call (-1: not seen then) and is overwritten with this call's, so a
    landmark first seen now enters the sum at the next call (its initial error is no loss).

    The belief gain (m^2) is its counterpart in the belief, over exactly the same landmarks: the drop of
    tr Sigma_jj, the trace of each landmark's 2x2 marginal position covariance, i.e. what a consistent filter
    expects the squared error to drop by (E|estimate_j - true_j|^2 = tr Sigma_jj; Thrun, Burgard & Fox ch. 3).
    ``traces`` (n,) holds each landmark's trace of the last call, written in step with ``errors``.
    """
    e0 = true_pose[0] - mean[0]
    e1 = true_pose[1] - mean[1]
    e2 = wrap_angle(true_pose[2] - mean[2])
    a, b, c = cov[0, 0], cov[0, 1], cov[0, 2]
    d, e, f = cov[1, 1], cov[1, 2], cov[2, 2]
    # e^T Sigma_xx^-1 e by cofactors of the symmetric 3x3 pose block.
    c00 = d * f - e * e
    c01 = c * e - b * f
    c02 = b * e - c * d
    c11 = a * f - c * c
    c12 = b * c - a * e
    c22 = a * d - b * b
    det = a * c00 + b * c01 + c * c02
    nees = (
        c00 * e0 * e0 + c11 * e1 * e1 + c22 * e2 * e2 + 2.0 * (c01 * e0 * e1 + c02 * e0 * e2 + c12 * e1 * e2)
    ) / det

    n = observed.shape[0]
    squared, seen = 0.0, 0
    worst = 0.0
    gain = 0.0
    belief = 0.0
    for j in range(n):
        lj = 3 + 2 * j
        if observed[j]:
            dx = mean[lj] - true_landmarks[j, 0]
            dy = mean[lj + 1] - true_landmarks[j, 1]
            error = dx * dx + dy * dy
            squared += error
            p, q, r = cov[lj, lj], cov[lj, lj + 1], cov[lj + 1, lj + 1]
            if errors[j] >= 0.0:
                gain += errors[j] - error
                belief += traces[j] - (p + r)
            errors[j] = error
            traces[j] = p + r
            seen += 1
            largest = 0.5 * (p + r) + math.sqrt(0.25 * (p - r) * (p - r) + q * q)
            worst = max(worst, largest)
        else:
            worst = np.inf
            errors[j] = -1.0
    rmse = math.sqrt(squared / seen) if seen else 0.0

    closures = 0
    for i in range(read_ids.shape[0]):
        j = read_ids[i]
        if last_seen[j] >= 0 and t - last_seen[j] >= loop_gap:
            closures += 1
        last_seen[j] = t
    return nees, rmse, closures, worst, seen, gain, belief
