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

import math

import numpy as np
from gymnasium import spaces

from ..envs.observation import ObservationLayout
from ..envs.observation_codes import CLIP

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
    out[:] = 0.0
    slots = out.shape[0] // TEAMMATE_FEATURES
    if slots == 0 or n_robots == 1:
        return
    i = 3 * robot
    x, y, theta = mean[i], mean[i + 1], mean[i + 2]
    others = [r for r in range(n_robots) if r != robot]
    offsets = np.array([[mean[3 * r] - x, mean[3 * r + 1] - y] for r in others])
    order = np.argsort(np.hypot(offsets[:, 0], offsets[:, 1]), kind="stable")[:slots]
    c, s = math.cos(theta), math.sin(theta)
    for slot, k in enumerate(order):
        j = 3 * others[k]
        dx, dy = offsets[k]
        relative = cov[j : j + 2, j : j + 2] + cov[i : i + 2, i : i + 2] - cov[j : j + 2, i : i + 2]
        relative = relative - cov[i : i + 2, j : j + 2]
        half_trace = 0.5 * (relative[0, 0] + relative[1, 1])
        turn = mean[j + 2] - theta
        o = TEAMMATE_FEATURES * slot
        out[o] = 1.0
        out[o + 1] = (c * dx + s * dy) / half_size
        out[o + 2] = (-s * dx + c * dy) / half_size
        out[o + 3] = math.sin(turn)
        out[o + 4] = math.cos(turn)
        out[o + 5] = math.log(max(half_trace, 1e-300)) / 10.0
    np.clip(out, -CLIP, CLIP, out=out)
