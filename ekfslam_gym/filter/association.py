"""Unknown data association for the EKF-SLAM: which initialised landmark each reading comes from, if any.

Methods: ``nearest`` (each reading alone takes its most likely landmark among those inside the Mahalanobis
gate: individual compatibility nearest neighbour) and ``jcbc`` (joint compatibility branch and bound, Neira &
Tardos, IEEE T-RA 17(6), 2001: the readings of one step are paired jointly, so two landmarks closer than the
gate, or clutter beside a landmark, are told apart by the correlations the individual test ignores). The kernels
are in ``association_kernels``; this module holds the gates, computed once without scipy.

Gates are chi-squared quantiles of even degrees of freedom 2k, whose distribution function has a closed form,
P(X <= x) = P(Poisson(x / 2) >= k), inverted here by bisection.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import numpy as np

METHODS: dict[str, int] = {"nearest": 1, "jcbc": 2}  # = association_kernels.METHOD_*, without loading numba

# JCBC's search stops after this many hypothesis nodes and keeps the best found (bounds the cost of a step).
MAX_NODES = 20000


class UnknownCorrection(NamedTuple):
    """What ``EKFSLAM.correct_unknown`` did with each reading.

    slots (m,) int64: the landmark slot each reading was used for (matched or newly initialised), -1 where the
    reading was discarded. new (m,) bool: the reading initialised its slot. forgotten (k,) int64: tentative
    landmarks dropped by this call (their slots are free again). delta: the change of log det Sigma.
    """

    slots: np.ndarray
    new: np.ndarray
    forgotten: np.ndarray
    delta: float


def _chi2_even_cdf(x: float, half_dof: int) -> float:
    """P(X <= x) for X ~ chi2(2 half_dof): 1 - exp(-x/2) sum_{i < half_dof} (x/2)^i / i!."""
    if x <= 0.0:
        return 0.0
    lam = 0.5 * x
    log_terms = [-lam + i * math.log(lam) - math.lgamma(i + 1) for i in range(half_dof)]
    top = max(log_terms)
    tail = math.exp(top) * sum(math.exp(t - top) for t in log_terms)
    return 1.0 - tail


def chi2_even_ppf(prob: float, dof: int) -> float:
    """The ``prob`` quantile of chi2 with an even number ``dof`` of degrees of freedom (to ~1e-12 relative)."""
    if not (isinstance(dof, (int, np.integer)) and dof >= 2 and dof % 2 == 0):
        raise ValueError(f"dof must be an even integer >= 2, got {dof!r}")
    if not 0.0 < prob < 1.0:
        raise ValueError(f"prob must lie in (0, 1), got {prob!r}")
    half = int(dof) // 2
    if half == 1:
        return -2.0 * math.log1p(-prob)
    lo, hi = 0.0, float(dof)
    while _chi2_even_cdf(hi, half) < prob:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if _chi2_even_cdf(mid, half) < prob:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-13 * hi:
            break
    return 0.5 * (lo + hi)


@lru_cache(maxsize=32)
def _gate_table(prob: float, size: int) -> np.ndarray:
    # Writable on purpose: the compiled kernels' signatures take plain arrays. Nobody writes to it.
    return np.array([chi2_even_ppf(prob, 2 * k) for k in range(1, size + 1)])


def gate_table(prob: float, pairings: int) -> np.ndarray:
    """chi2(2k, prob) for k = 1..K, K >= ``pairings`` (computed once per 64 entries and cached)."""
    check_probability(prob, "gate")
    size = 64 * max(1, -(-int(pairings) // 64))
    return _gate_table(float(prob), size)


def check_probability(value: float, name: str) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value < 1.0:
        raise ValueError(f"{name} must be a probability in (0, 1), got {value!r}")


def check_method(kind: str) -> int:
    """The kernels' code of association ``kind``; ``known`` has none (the sensor's ids go to ``correct``)."""
    if kind not in METHODS:
        raise ValueError(
            f"association.kind must be one of {sorted(METHODS)} to associate from the readings, got {kind!r}"
            + (" (known association uses the sensor's ids: EKFSLAM.correct)" if kind == "known" else "")
        )
    return METHODS[kind]
