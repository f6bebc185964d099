"""Two groups of models compared on the same evaluation seeds: the difference of their IQMs with a 95 % bootstrap
CI that resamples the seeds, keeping each seed's episodes of every model together.

Models evaluated on the same seeds share each seed's world and noise, so a hard seed is hard for both groups;
resampling seeds rather than episodes (a cluster bootstrap) removes that shared part from the difference's
interval, which is then narrower than the two groups' own intervals suggest when the seed explains much of a
metric. The IQM and the percentile bootstrap are ``aggregate``'s (Agarwal et al., NeurIPS 2021).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .metrics import _iqm_along_last_axis, iqm

Model = Sequence[Mapping[str, float]]  # one model's episodes, each with its "seed"


@dataclass(frozen=True)
class PairedDifference:
    """IQM of group a, of group b, a - b, and the seed-resampled bootstrap CI of a - b."""

    metric: str
    a: float
    b: float
    difference: float
    ci: tuple[float, float]
    seeds: int


def _by_seed(models: Sequence[Model], metric: str, side: str) -> tuple[list[int], np.ndarray]:
    """(seeds, seeds x models array of the metric); every model must hold each seed exactly once."""
    if not models:
        raise ValueError(f"group {side} holds no models")
    seeds: list[int] | None = None
    columns = []
    for index, episodes in enumerate(models):
        by_seed = {int(e["seed"]): float(e[metric]) for e in episodes}
        if len(by_seed) != len(episodes):
            raise ValueError(f"model {index} of group {side} holds a seed more than once")
        if seeds is None:
            seeds = sorted(by_seed)
        elif sorted(by_seed) != seeds:
            raise ValueError(f"model {index} of group {side} was evaluated on other seeds than model 0")
        columns.append([by_seed[s] for s in seeds])
    assert seeds is not None
    return seeds, np.array(columns, dtype=float).T


def paired_difference(
    a: Sequence[Model],
    b: Sequence[Model],
    metric: str,
    *,
    n_resamples: int = 2000,
    confidence: float = 0.95,
    seed: int = 0,
) -> PairedDifference:
    """IQM over the pooled episodes of the models in ``a`` minus that of ``b``, each model evaluated on the same
    seeds, with a seeded percentile-bootstrap CI over the seeds (NaNs left out of each IQM, as ``aggregate``)."""
    seeds_a, values_a = _by_seed(a, metric, "a")
    seeds_b, values_b = _by_seed(b, metric, "b")
    if seeds_a != seeds_b:
        raise ValueError(f"the groups were evaluated on different seeds ({len(seeds_a)} and {len(seeds_b)})")
    first, second = iqm(values_a), iqm(values_b)
    rng = np.random.default_rng(seed)
    n = len(seeds_a)
    draws = rng.integers(0, n, size=(n_resamples, n))
    if np.isnan(values_a).any() or np.isnan(values_b).any():  # each resample drops its own NaNs
        boot = np.array([iqm(values_a[rows]) - iqm(values_b[rows]) for rows in draws])
        boot = boot[~np.isnan(boot)]
    else:  # (resamples, seeds x models) at once
        boot = _iqm_along_last_axis(values_a[draws].reshape(n_resamples, -1))
        boot = boot - _iqm_along_last_axis(values_b[draws].reshape(n_resamples, -1))
    tail = 100.0 * (1.0 - confidence) / 2.0
    lo, hi = np.percentile(boot, [tail, 100.0 - tail]) if boot.size else (math.nan, math.nan)
    return PairedDifference(metric, first, second, first - second, (float(lo), float(hi)), n)
