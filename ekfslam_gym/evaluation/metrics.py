"""Evaluation metrics: trajectory and map errors, filter consistency, and robust aggregates over episodes.

Pure functions on arrays, no I/O and no env: the evaluator records an episode and calls these, and a test can
check each on a case with a known answer.

- ``ate``: absolute trajectory error, RMSE of estimated vs true positions, no alignment (the filter starts at
  the true pose, so the estimate is already in the world frame and aligning it would hide drift).
- ``landmark_errors``: RMSE of the seen landmarks and the number of landmarks never seen.
- ``nees`` / ``nees_bounds``: normalised estimation error squared of a Gaussian estimate and its two-sided
  chi-squared bounds; ``anees`` averages NEES and ``fraction_in_bounds`` counts the steps inside the bounds.
- ``gain_correlation``: Pearson and Spearman correlation of two per-step series (the gain the filter believes
  in, the drop of the seen landmarks' position variances, and the truth gain, the drop of their squared error).
- ``iqm`` / ``bootstrap_ci``: the interquartile mean (robust to a few failed episodes, as in rliable) and a
  seeded percentile-bootstrap confidence interval of it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..angles import wrap_angles

__all__ = [
    "ate",
    "anees",
    "bootstrap_ci",
    "fraction_in_bounds",
    "gain_correlation",
    "iqm",
    "landmark_errors",
    "nees",
    "nees_bounds",
    "pose_errors",
]


def pose_errors(estimated: np.ndarray, true: np.ndarray) -> np.ndarray:
    """true - estimated for (T, 3) poses (x m, y m, theta rad), the heading difference wrapped."""
    estimated = np.asarray(estimated, dtype=float)
    true = np.asarray(true, dtype=float)
    if estimated.shape != true.shape or estimated.shape[-1] != 3:
        raise ValueError(f"poses must both be (..., 3), got {estimated.shape} and {true.shape}")
    errors = true - estimated
    errors[..., 2] = wrap_angles(errors[..., 2])
    return errors


def ate(estimated_xy: np.ndarray, true_xy: np.ndarray) -> float:
    """Absolute trajectory error (m): sqrt of the mean squared position error over the (T, 2) trajectories.

    No alignment. Extra columns (a heading) are ignored, so (T, 3) poses may be passed directly.
    """
    estimated_xy = np.asarray(estimated_xy, dtype=float)
    true_xy = np.asarray(true_xy, dtype=float)
    if estimated_xy.shape != true_xy.shape or estimated_xy.ndim != 2 or estimated_xy.shape[1] < 2:
        raise ValueError(f"trajectories must both be (T, >=2), got {estimated_xy.shape} and {true_xy.shape}")
    if estimated_xy.shape[0] == 0:
        return math.nan
    squared = np.sum((estimated_xy[:, :2] - true_xy[:, :2]) ** 2, axis=1)
    return float(np.sqrt(np.mean(squared)))


def landmark_errors(estimated: np.ndarray, true: np.ndarray, seen: np.ndarray) -> tuple[float, int]:
    """(RMSE in m of the seen landmarks' (n, 2) position estimates, number of landmarks not seen).

    The RMSE is NaN when no landmark was seen: there is no map to score, and 0 would read as a perfect one.
    """
    estimated = np.asarray(estimated, dtype=float).reshape(-1, 2)
    true = np.asarray(true, dtype=float).reshape(-1, 2)
    seen = np.asarray(seen, dtype=bool).reshape(-1)
    if not (estimated.shape == true.shape and seen.shape[0] == true.shape[0]):
        raise ValueError(
            f"shapes disagree: estimated {estimated.shape}, true {true.shape}, seen {seen.shape}"
        )
    missed = int(seen.size - seen.sum())
    if not seen.any():
        return math.nan, missed
    squared = np.sum((estimated[seen] - true[seen]) ** 2, axis=1)
    return float(np.sqrt(np.mean(squared))), missed


def nees(errors: np.ndarray, covariances: np.ndarray) -> np.ndarray:
    """Normalised estimation error squared e^T P^-1 e for (T, d) errors and (T, d, d) covariances -> (T,).

    A consistent estimator's NEES is chi-squared with d degrees of freedom (mean d). A step whose covariance
    is not positive definite, or whose error is not finite, gives NaN.
    """
    errors = np.asarray(errors, dtype=float)
    covariances = np.asarray(covariances, dtype=float)
    if errors.ndim == 1:
        errors, covariances = errors[None], covariances[None]
    if covariances.shape != errors.shape + errors.shape[-1:]:
        raise ValueError(f"covariances must be (T, d, d) for (T, d) errors, got {covariances.shape}")
    out = np.full(errors.shape[0], np.nan)
    finite = np.all(np.isfinite(errors), axis=1) & np.all(np.isfinite(covariances), axis=(1, 2))
    for t in np.flatnonzero(finite):
        try:
            chol = np.linalg.cholesky(covariances[t])
        except np.linalg.LinAlgError:
            continue
        whitened = np.linalg.solve(chol, errors[t])
        out[t] = float(whitened @ whitened)
    return out


def nees_bounds(dim: int = 3, n_runs: int = 1, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided chi-squared bounds of the average NEES of ``n_runs`` independent runs of a ``dim``-dimensional
    state: chi2.ppf([a/2, 1 - a/2], n_runs * dim) / n_runs with a = 1 - confidence.

    ``n_runs = 1`` gives the per-step bounds of a single run, (0.216, 9.35) for dim 3 at 95 %.
    """
    from scipy import stats  # here, not at import: scipy.stats costs a second at start-up

    if dim < 1 or n_runs < 1 or not 0.0 < confidence < 1.0:
        raise ValueError(
            f"need dim >= 1, n_runs >= 1 and 0 < confidence < 1, got {dim}, {n_runs}, {confidence}"
        )
    alpha = 1.0 - confidence
    lo, hi = stats.chi2.ppf([0.5 * alpha, 1.0 - 0.5 * alpha], n_runs * dim) / n_runs
    return float(lo), float(hi)


def anees(nees_values: np.ndarray) -> float:
    """Average NEES over the finite values (NaN if there are none)."""
    values = np.asarray(nees_values, dtype=float)
    values = values[np.isfinite(values)]
    return float(values.mean()) if values.size else math.nan


def fraction_in_bounds(values: np.ndarray, bounds: tuple[float, float]) -> float:
    """Fraction of the values inside [lo, hi]; a NaN counts as outside (a failed filter is not consistent)."""
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return math.nan
    inside = (values >= bounds[0]) & (values <= bounds[1])
    return float(inside.mean())


def gain_correlation(belief: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """(Pearson r, Spearman rho) of two equally long per-step series, over the steps where both are finite.

    NaN where undefined: fewer than 3 such steps, or either series constant on them (no variation to
    correlate). Spearman is Pearson on the ranks (ties averaged), so it is not ruled by a few large steps
    (the first corrections of newly seen landmarks).
    """
    from scipy import stats  # here, not at import: scipy.stats costs a second at start-up

    belief = np.asarray(belief, dtype=float).reshape(-1)
    truth = np.asarray(truth, dtype=float).reshape(-1)
    if belief.shape != truth.shape:
        raise ValueError(f"the series must be equally long, got {belief.size} and {truth.size}")
    keep = np.isfinite(belief) & np.isfinite(truth)
    belief, truth = belief[keep], truth[keep]
    if belief.size < 3 or np.ptp(belief) == 0.0 or np.ptp(truth) == 0.0:
        return math.nan, math.nan
    return _pearson(belief, truth), _pearson(stats.rankdata(belief), stats.rankdata(truth))


def _pearson(x: np.ndarray, y: np.ndarray) -> float:
    x = x - x.mean()
    y = y - y.mean()
    denominator = math.sqrt(float(x @ x) * float(y @ y))
    if denominator == 0.0:
        return math.nan
    return float(np.clip((x @ y) / denominator, -1.0, 1.0))


def _iqm_along_last_axis(values: np.ndarray) -> np.ndarray:
    from scipy import stats  # here, not at import: scipy.stats costs a second at start-up

    return stats.trim_mean(values, 0.25, axis=-1)


def iqm(values: np.ndarray) -> float:
    """Interquartile mean: the mean of the middle 50 % (scipy's trim_mean with 25 % cut from each end).

    NaNs are dropped first (an episode whose metric is undefined); NaN if nothing is left.
    """
    values = np.asarray(values, dtype=float).reshape(-1)
    values = values[~np.isnan(values)]
    if values.size == 0:
        return math.nan
    return float(_iqm_along_last_axis(values))


def bootstrap_ci(
    values: np.ndarray,
    statistic: Callable[[np.ndarray], np.ndarray] = _iqm_along_last_axis,
    *,
    n_resamples: int = 2000,
    confidence: float = 0.95,
    seed: int = 0,
) -> tuple[float, float]:
    """Percentile-bootstrap confidence interval of ``statistic`` (default the IQM), seeded.

    ``statistic`` maps a (B, n) array of resamples to (B,) values along its last axis. NaNs are dropped;
    with one value the interval is that value, with none it is (NaN, NaN).
    """
    values = np.asarray(values, dtype=float).reshape(-1)
    values = values[~np.isnan(values)]
    if values.size == 0:
        return math.nan, math.nan
    if values.size == 1:
        return float(values[0]), float(values[0])
    rng = np.random.default_rng(seed)
    resamples = values[rng.integers(0, values.size, size=(n_resamples, values.size))]
    estimates = np.asarray(statistic(resamples), dtype=float)
    alpha = 1.0 - confidence
    lo, hi = np.quantile(estimates, [0.5 * alpha, 1.0 - 0.5 * alpha])
    return float(lo), float(hi)
