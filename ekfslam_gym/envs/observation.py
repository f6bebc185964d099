"""The observation: the filter's belief, the wall scan and a coverage memory, as one normalised float32 vector.

Layout of the flat vector (``ObservationLayout`` is its one definition: the Box and Dict spaces, the compiled
kernel and the agents all read it; the Dict variant uses the same names):

| part | size | contents (all clipped to [-CLIP, CLIP]) |
|---|---|---|
| `pose` | 4 | estimated (x, y) relative to the world's centre / half its larger side; sin and cos of heading |
| `pose_cov` | 3 | ln of the pose variances (x, y, theta) / 10 |
| `landmarks` | 4 k | the k seen landmarks nearest the pose estimate, nearest first: [seen flag, x and y of the estimate in the robot's frame / sensor max_range, ln(trace of its 2x2 covariance / 2) / 10]; slots beyond the seen landmarks are all zero |
| `globals` | 3 | mean ln variance of the map (ln det Sigma_mm / 2n / 10), fraction of landmarks seen, time left (1 at reset, falling linearly to exactly 0 at the episode's step limit) |
| `scan` | B | wall distances along B beams fixed to the robot / scan_max_range (1 = nothing within range) |
| `coverage` | G*G | a robot-centred window, turned with the estimated heading and reaching grid_extent m each side, of the coverage memory: 1 where the sensor has looked (a memory cell whose centre was within range and field of view of the pose *estimate* at some step; walls ignored, the belief has none) or outside the world, else 0. Row-major: row 0 is furthest to the left, column 0 furthest behind, so the robot faces along the rows towards the last column |
| `coverage_coarse` | C*C | the same, coarser and wider (coarse_grid cells reaching coarse_extent m): each cell the fraction of it looked at, so that beyond the fine window the robot still knows where the unexplored part of the world lies (0 disables it) |

Everything is computed by one compiled kernel writing into a preallocated vector: the env is stepped millions
of times and each numpy call costs microseconds.

``observation.last_action`` (Dict observations only, off by default) adds the key ``last_action``: the action
the last env step executed (zeros after reset), a float32 one-hot of the primitive for a Discrete action, else
the clipped action, in the action's Box (``last_action_space``).

The belief image (``observation.belief_image``, Dict observations only, off by default) is a further key,
``belief_image``: float32 (3, S, S) in [0, 1], S = ``belief_size`` (16), a robot-centred window reaching
``belief_extent`` m (8) to each side, centred on the pose *estimate* and turned with its heading exactly like
the coverage window (row 0 furthest to the left, column 0 furthest behind). It is memory and a map for a
convolutional policy (``ekfslam_gym.agents.extractors.BeliefCNN``), drawn from the belief alone, never from the true pose,
landmarks or walls:

| channel | contents |
|---|---|
| 0 | the coverage memory as above, each cell the fraction of it looked at (1 outside the world) |
| 1 | every seen landmark's *estimate* in the cell holding it, valued by its certainty 1 / (1 + sqrt(tr Sigma_jj) / cell size) (1/2 when the expected position error is one cell; the largest where several share a cell); 0 elsewhere |
| 2 | walls as the wall scan has seen them: a wall memory laid out like the coverage memory, where every control step marks the cells of the scan's endpoints that hit a wall before `scan_max_range`, placed from the pose *estimate*; each image cell 1 if any memory cell under it holds a wall (and outside the world), else 0 |

Computed by its own compiled kernel only when enabled; with it off nothing of it runs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from gymnasium import spaces

from ..sim.sensor import SensorParams
from .config import ObservationConfig
from .observation_codes import (
    BELIEF_CHANNELS,
    CLIP,
    COARSE_EXTENT,
    GRID_EXTENT,
    LANDMARK_FEATURES,
    MAX_RANGE,
    MEMORY_RESOLUTION,
    PARTS,
    SCAN_MAX_RANGE,
)


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


def belief_image_space(observation: ObservationConfig) -> spaces.Box:
    """The ``belief_image`` key's space: float32 (channels, belief_size, belief_size) in [0, 1]."""
    size = observation.belief_size
    return spaces.Box(0.0, 1.0, shape=(BELIEF_CHANNELS, size, size), dtype=np.float32)


def last_action_space(action_space: spaces.Space) -> spaces.Box:
    """The ``last_action`` key's space: a float32 one-hot (n,) for a Discrete(n) action, else the action's Box."""
    if isinstance(action_space, spaces.Discrete):
        return spaces.Box(0.0, 1.0, shape=(int(action_space.n),), dtype=np.float32)
    if isinstance(action_space, spaces.Box):
        return spaces.Box(action_space.low, action_space.high, dtype=np.float32)
    raise TypeError(f"observation.last_action supports Discrete and Box actions, got {action_space}")


def observation_space(
    layout: ObservationLayout, observation: ObservationConfig, action_space: spaces.Space | None = None
) -> spaces.Space:
    """The env's observation space: the layout's Box or Dict, plus ``belief_image`` and ``last_action`` (of
    ``action_space``) when they are enabled."""
    space = layout.space(observation.kind)
    if observation.belief_image:
        space = spaces.Dict({**space.spaces, "belief_image": belief_image_space(observation)})
    if observation.last_action:
        if action_space is None:
            raise ValueError("observation.last_action needs the action space")
        space = spaces.Dict({**space.spaces, "last_action": last_action_space(action_space)})
    return space


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


def make_memory(bounds: np.ndarray, resolution: float) -> np.ndarray:
    """An empty coverage memory over the world's bounds, ``resolution`` m per cell, rows along y."""
    cols = max(1, int(math.ceil((bounds[2] - bounds[0]) / resolution)))
    rows = max(1, int(math.ceil((bounds[3] - bounds[1]) / resolution)))
    return np.zeros((rows, cols))
