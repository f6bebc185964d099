"""Each robot's observation: the single-robot observation of its own pose belief and the shared map, then its
teammates.

The first part is ``ekfslam_gym.envs.observation``'s flat vector (its ``ObservationLayout``, filled by the same
compiled kernel), read from the joint belief as robot i sees it: robot i's pose and its variances, the k seen
landmarks nearest its pose estimate, the map's mean ln variance (ln det Sigma_mm / 2n / 10, Sigma_mm the joint
map block, shared by the team), the fraction seen and the time left, robot i's wall scan, and the windows of
the team's shared coverage memory centred on robot i. Then ``team.teammate_slots`` teammates, nearest
(estimated) first, ``TEAMMATE_FEATURES`` each:

| feature | meaning |
|---|---|
| 0 | 1 for a teammate, 0 for an empty slot (all its features 0) |
| 1, 2 | the teammate's estimated position in robot i's frame (forward, left), / half the world's larger side |
| 3, 4 | sin and cos of its estimated heading relative to robot i's |
| 5 | ln of half the trace of the covariance of its position relative to robot i's (Sigma_jj + Sigma_ii - Sigma_ij - Sigma_ji, the 2 x 2 position blocks), / 10 |

Every entry is clipped to [-CLIP, CLIP], as the single-robot observation's.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from ..envs.observation import ObservationLayout
from ..envs.observation_codes import CLIP
from . import kernels

TEAMMATE_FEATURES = 6


def team_observation_space(layout: ObservationLayout, teammate_slots: int) -> spaces.Box:
    """One robot's observation space: the single-robot layout's vector, then the teammate slots."""
    size = layout.size + TEAMMATE_FEATURES * teammate_slots
    return spaces.Box(-CLIP, CLIP, shape=(size,), dtype=np.float32)


def fill_teammates(
    out: np.ndarray, robot: int, mean: np.ndarray, cov: np.ndarray, n_robots: int, half_size: float
) -> None:
    """Write robot ``robot``'s teammate slots into ``out`` (TEAMMATE_FEATURES per slot, zeros beyond the
    teammates) from the joint belief (mean, cov), robots' poses at 3r..3r+2."""
    kernels.fill_teammates(out, robot, mean, cov, n_robots, half_size, CLIP, TEAMMATE_FEATURES)
