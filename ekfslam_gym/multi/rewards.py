"""The team's reward terms: the single-robot env's ``REWARD_TERMS``, taken over the team.

One reward for the whole team, the same for every robot (a cooperative game: Boutilier's MMDP, a Dec-POMDP
when each robot sees only its observation), weighted by the same ``reward`` section as the single-robot env:

| term | team value per control step |
|---|---|
| info_gain | log det Sigma_{t-1} - log det Sigma_t of the joint covariance (every pose and every landmark) |
| collision | -1 per robot in contact with a wall |
| step_cost | -1 |
| coverage | m^2 of the world the team's sensors look at for the first time (the shared coverage memory) |
| pose_variance | -sum over robots of tr Sigma_xy, m^2 |

Each robot's own share of the per-robot terms (its wall contact, its pose variance) is reported apart in its
info (``robot_terms``); the team terms are their sums. The information gain telescopes, as the single-robot
env's does, to log det Sigma_0 - log det Sigma_T.
"""

from __future__ import annotations

import numpy as np

from ..envs.rewards import REWARD_NAMES

ROBOT_TERMS = ("collision", "pose_variance")


def robot_terms(collided: np.ndarray, cov: np.ndarray, n_robots: int) -> np.ndarray:
    """Each robot's per-robot terms of one control step, (N, 2) in ``ROBOT_TERMS`` order: -1 if it touched a
    wall, and -tr of its position covariance (m^2), from the joint covariance ``cov``."""
    out = np.empty((n_robots, 2))
    out[:, 0] = -collided.astype(np.float64)
    for r in range(n_robots):
        out[r, 1] = -(cov[3 * r, 3 * r] + cov[3 * r + 1, 3 * r + 1])
    return out


def team_terms(log_det_before: float, log_det_after: float, per_robot: np.ndarray, covered: float) -> dict:
    """Every term's unweighted team value for one control step, by name, in ``REWARD_NAMES`` order."""
    sums = per_robot.sum(axis=0)
    values = {
        "info_gain": log_det_before - log_det_after,
        "collision": float(sums[0]) if sums[0] else -0.0,
        "step_cost": -1.0,
        "coverage": float(covered),
        "pose_variance": float(sums[1]),
    }
    return {name: values[name] for name in REWARD_NAMES}
