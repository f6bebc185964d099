"""Filter consistency under an agent's driving: pose NEES, map NEES and NIS over time, with their chi-squared
bands (Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to Tracking and Navigation*, ch. 5.4).

Per run and step: the pose NEES (3 dof, the env's ``info["pose_nees"]``); the map NEES of the landmarks the
filter has initialised, e_m^T Sigma_mm^-1 e_m with 2 n_seen dof; and the NIS of the step's readings of
landmarks already in the map, nu^T S^-1 nu with 2 m dof, from the predicted belief (a copy of the filter
taken before the step, moved by the step's odometry: the innovation the correction saw, linearised at the
prediction, for every variant). Over M runs, each quantity's sum over runs divided by its summed dof is
consistent when it lies within chi2.ppf([0.025, 0.975], D) / D, D the summed dof (exact for independent
runs); ``ConsistencyRun`` holds those per-step sums.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .interface import check_action_kind

QUANTITIES = ("pose_nees", "map_nees", "nis")


@dataclass
class ConsistencyRun:
    """Per-step sums over runs (T,) of each quantity and of its degrees of freedom, and the runs behind them."""

    label: str
    sums: dict[str, np.ndarray]
    dofs: dict[str, np.ndarray]
    runs: int

    def normalised(self, quantity: str) -> np.ndarray:
        """Sum over runs / summed dof per step: 1 when consistent (NaN where no dof)."""
        dof = self.dofs[quantity]
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(dof > 0, self.sums[quantity] / np.maximum(dof, 1), np.nan)

    def bands(self, quantity: str, confidence: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
        """Per-step chi-squared bounds of ``normalised(quantity)``."""
        from scipy import stats  # here, not at import: scipy.stats costs a second at start-up

        dof = np.maximum(self.dofs[quantity], 1)
        alpha = 1.0 - confidence
        lo = stats.chi2.ppf(0.5 * alpha, dof) / dof
        hi = stats.chi2.ppf(1.0 - 0.5 * alpha, dof) / dof
        missing = self.dofs[quantity] == 0
        return np.where(missing, np.nan, lo), np.where(missing, np.nan, hi)

    def fraction_inside(self, quantity: str, confidence: float = 0.95) -> float:
        """Fraction of the steps (with any dof) whose normalised value lies within the bands."""
        value = self.normalised(quantity)
        lo, hi = self.bands(quantity, confidence)
        defined = self.dofs[quantity] > 0
        if not defined.any():
            return float("nan")
        inside = (value >= lo) & (value <= hi)
        return float(inside[defined].mean())

    def summary(self) -> dict[str, Any]:
        """JSON-safe: per quantity, the median normalised value and the fraction of steps inside the bands."""
        out: dict[str, Any] = {
            "label": self.label,
            "runs": self.runs,
            "steps": int(self.sums["pose_nees"].size),
        }
        for q in QUANTITIES:
            value = self.normalised(q)
            finite = value[np.isfinite(value)]
            out[q] = {
                "median": float(np.median(finite)) if finite.size else None,
                "inside": self.fraction_inside(q),
            }
        return out


def map_nees(
    mean: np.ndarray, cov: np.ndarray, observed: np.ndarray, true_landmarks: np.ndarray
) -> tuple[float, int]:
    """(NEES, dof) of the initialised landmarks jointly; (0, 0) when none is."""
    slots = np.flatnonzero(observed)
    if slots.size == 0:
        return 0.0, 0
    index = (3 + 2 * slots[:, None] + np.arange(2)).ravel()
    error = mean[index] - true_landmarks[slots].ravel()
    block = cov[np.ix_(index, index)]
    return float(error @ np.linalg.solve(block, error)), int(index.size)


def innovation_nis(
    predicted, ids: np.ndarray, z: np.ndarray, measurement_cov: np.ndarray
) -> tuple[float, int]:
    """(NIS, dof) of the readings of landmarks already in ``predicted`` (an ``EKFSLAM`` after its prediction),
    all readings of the step jointly; (0, 0) when none qualifies."""
    from ..angles import wrap_angle
    from ..filter.models import range_bearing

    keep = [i for i, j in enumerate(ids) if predicted.observed[j]]
    if not keep:
        return 0.0, 0
    mean, cov = predicted.mean, predicted.cov
    n = mean.size
    H = np.zeros((2 * len(keep), n))
    nu = np.empty(2 * len(keep))
    for row, i in enumerate(keep):
        lj = 3 + 2 * int(ids[i])
        zhat, hx, hm = range_bearing(mean[:3], mean[lj : lj + 2], predicted.min_range)
        H[2 * row : 2 * row + 2, :3] = hx
        H[2 * row : 2 * row + 2, lj : lj + 2] = hm
        nu[2 * row] = z[i, 0] - zhat[0]
        nu[2 * row + 1] = wrap_angle(z[i, 1] - zhat[1])
    S = H @ cov @ H.T + np.kron(np.eye(len(keep)), measurement_cov)
    return float(nu @ np.linalg.solve(S, nu)), int(nu.size)


def run_consistency(
    env_factory, agent, seeds, steps: int, label: str, decide_every: int = 1
) -> ConsistencyRun:
    """Drive ``agent`` for ``steps`` steps in a fresh env from ``env_factory()`` per seed; sums per step.

    The env must take one control step per env step (``action.hold`` 1), so that every control step is
    sampled. A policy trained with macro actions held for N control steps drives the same way with
    ``decide_every=N``: it is asked every N steps and its action repeated in between. Steps after an episode
    ended early add nothing (their dof stays 0 for that run).
    """
    if decide_every < 1:
        raise ValueError(f"decide_every must be >= 1, got {decide_every}")
    sums = {q: np.zeros(steps) for q in QUANTITIES}
    dofs = {q: np.zeros(steps, dtype=np.int64) for q in QUANTITIES}
    seeds = list(seeds)
    for seed in seeds:
        env = env_factory()
        observation, _ = env.reset(seed=int(seed))
        agent.reset(env, seed=int(seed))
        check_action_kind(agent, env)
        base = env.unwrapped
        if base.config.action.steps != 1:
            raise ValueError("the consistency report needs one control step per env step (action.hold 1)")
        truth = base.true_landmarks
        Q = base.filter.measurement_noise
        for t in range(steps):
            prior = base.filter.copy()
            if t % decide_every == 0:
                action = agent.act(observation)
            observation, _, terminated, truncated, info = env.step(action)
            ekf = base.filter
            if info["filter_failed"]:
                break
            sums["pose_nees"][t] += info["pose_nees"]
            dofs["pose_nees"][t] += 3
            value, dof = map_nees(ekf.mean, ekf.cov, ekf.observed, truth)
            sums["map_nees"][t] += value
            dofs["map_nees"][t] += dof
            prior.predict(info["odometry"], control_cov=info["odometry_cov"])
            value, dof = innovation_nis(prior, info["readings"].ids, info["readings"].z, Q)
            sums["nis"][t] += value
            dofs["nis"][t] += dof
            if terminated or truncated:
                break
        env.close()
    return ConsistencyRun(label, sums, dofs, len(seeds))
