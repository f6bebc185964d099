"""The observation: the filter's belief, the wall scan and a coverage memory, as one normalised float32 vector.

Layout of the flat vector (``ObservationLayout`` is its one definition: the Box and Dict spaces, the compiled
kernel and the agents all read it; the Dict variant uses the same names):

========== ====== ================================================================================================
part       size   contents (all clipped to [-CLIP, CLIP])
========== ====== ================================================================================================
pose       4      estimated (x, y) relative to the world's centre / half its larger side; sin and cos of heading
pose_cov   3      ln of the pose variances (x, y, theta) / 10
landmarks  4 k    the k seen landmarks nearest the pose estimate, nearest first: [seen flag, x and y of the
                  estimate in the robot's frame / sensor max_range, ln(trace of its 2x2 covariance / 2) / 10];
                  slots beyond the seen landmarks are all zero
globals    3      mean ln variance of the map (ln det Sigma_mm / 2n / 10), fraction of landmarks seen, time left
                  (1 at reset, falling linearly to exactly 0 at the episode's step limit)
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
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from gymnasium import spaces
from numba import njit

from ..filter.kernels import det3
from ..sim.sensor import SensorParams
from .config import ObservationConfig

CLIP = 5.0
LANDMARK_FEATURES = 4
COARSE_SAMPLES = 4  # points per side averaged in each cell of the coarse window

PARTS = ("pose", "pose_cov", "landmarks", "globals", "scan", "coverage", "coverage_coarse")
# Positions of the parts in ``ObservationLayout.offsets`` (the kernel reads part i at offsets[i]:offsets[i + 1]).
POSE, POSE_COV, LANDMARKS, GLOBALS, SCAN, COVERAGE, COVERAGE_COARSE = range(len(PARTS))
# Positions in the array of ``observation_constants`` (the kernel's scales and window extents).
MAX_RANGE, SCAN_MAX_RANGE, MEMORY_RESOLUTION, GRID_EXTENT, COARSE_EXTENT = range(5)


@dataclass(frozen=True)
class ObservationLayout:
    """Where each part of the flat observation lies: its one definition.

    Built from the ``observation`` config and the sensor's beam count (``from_config``). ``sizes`` and
    ``slices`` (read-only mappings) name the parts present, in order (``coverage_coarse`` only when
    ``coarse_grid`` > 0); ``offsets`` (int64, len(PARTS) + 1, read-only) gives part i of ``PARTS`` at
    ``offsets[i]:offsets[i + 1]`` (an empty span when absent), which is all the compiled kernel is told.
    """

    k_nearest: int
    n_beams: int
    grid: int
    coarse_grid: int = 0
    sizes: Mapping[str, int] = field(init=False, repr=False, compare=False)
    slices: Mapping[str, slice] = field(init=False, repr=False, compare=False)
    offsets: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name, minimum in (("k_nearest", 1), ("n_beams", 1), ("grid", 1), ("coarse_grid", 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
                raise ValueError(f"ObservationLayout.{name} must be an integer >= {minimum}, got {value!r}")
        every = (
            4,
            3,
            LANDMARK_FEATURES * self.k_nearest,
            3,
            self.n_beams,
            self.grid * self.grid,
            self.coarse_grid * self.coarse_grid,
        )
        offsets = np.zeros(len(PARTS) + 1, dtype=np.int64)
        offsets[1:] = np.cumsum(every)
        offsets.flags.writeable = False
        sizes = {name: size for name, size in zip(PARTS, every) if size}
        slices = {
            name: slice(int(offsets[i]), int(offsets[i + 1])) for i, name in enumerate(PARTS) if every[i]
        }
        object.__setattr__(self, "sizes", MappingProxyType(sizes))
        object.__setattr__(self, "slices", MappingProxyType(slices))
        object.__setattr__(self, "offsets", offsets)

    def __reduce__(self):
        # Rebuilt from the four sizes: the read-only views are derived, and a mapping proxy does not pickle.
        return type(self), (self.k_nearest, self.n_beams, self.grid, self.coarse_grid)

    @classmethod
    def from_config(cls, observation: ObservationConfig, sensor: SensorParams) -> ObservationLayout:
        return cls(observation.k_nearest, sensor.n_beams, observation.grid, observation.coarse_grid)

    @property
    def size(self) -> int:
        """Length of the flat vector."""
        return int(self.offsets[-1])

    def space(self, kind: str = "box") -> spaces.Space:
        """The observation space: one ``Box`` of ``size``, or (kind ``"dict"``) a ``Dict`` of the parts."""
        if kind == "box":
            return spaces.Box(-CLIP, CLIP, shape=(self.size,), dtype=np.float32)
        if kind == "dict":
            return spaces.Dict(
                {
                    name: spaces.Box(-CLIP, CLIP, shape=(size,), dtype=np.float32)
                    for name, size in self.sizes.items()
                }
            )
        raise ValueError(f"kind must be box|dict, got {kind!r}")

    def part(self, observation: Any, name: str) -> np.ndarray:
        """Part ``name`` of a flat or a Dict observation (a view of the flat one)."""
        if isinstance(observation, Mapping):
            return np.asarray(observation[name])
        return np.asarray(observation)[..., self.slices[name]]

    def split(self, flat: np.ndarray) -> dict[str, np.ndarray]:
        """The Dict observation of a flat one (copies, in the order of the parts)."""
        return {name: flat[s].copy() for name, s in self.slices.items()}


def observation_constants(observation: ObservationConfig, sensor: SensorParams) -> np.ndarray:
    """The kernel's fixed scales and window extents, indexed by ``MAX_RANGE`` ... ``COARSE_EXTENT``."""
    values = np.empty(5)
    values[MAX_RANGE] = sensor.max_range
    values[SCAN_MAX_RANGE] = sensor.scan_max_range
    values[MEMORY_RESOLUTION] = observation.memory_resolution
    values[GRID_EXTENT] = observation.grid_extent
    values[COARSE_EXTENT] = observation.coarse_extent
    values.flags.writeable = False
    return values


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
def _window_side(offsets, part):
    """Side of the square window stored as part ``part`` (0 when absent)."""
    return int(math.sqrt(offsets[part + 1] - offsets[part]) + 0.5)


@njit(cache=True)
def fill_observation(
    out, offsets, constants, mean, cov, observed, log_det, pose_given_map, scan, memory, bounds, time_left
):
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
