"""Aggregates over episodes: the IQM of each metric with a seeded 95 % percentile-bootstrap CI, and the mean
(Agarwal et al., "Deep RL at the edge of the statistical precipice", NeurIPS 2021). Undefined values (NaN) are
left out of the aggregates.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from . import metrics
from .episode_metrics import METRIC_KEYS


def aggregate(
    episodes: Sequence[Mapping[str, float]],
    keys: Sequence[str] = METRIC_KEYS,
    *,
    n_resamples: int = 2000,
    seed: int = 0,
) -> dict[str, dict[str, Any]]:
    """IQM, 95 % bootstrap CI of the IQM (seeded) and mean of each metric over episodes (NaNs left out)."""
    out: dict[str, dict[str, Any]] = {}
    for key in keys:
        values = np.array([float(e[key]) for e in episodes], dtype=float)
        finite = values[np.isfinite(values)]
        lo, hi = metrics.bootstrap_ci(finite, n_resamples=n_resamples, seed=seed)
        out[key] = {
            "iqm": metrics.iqm(finite),
            "ci": [lo, hi],
            "mean": float(finite.mean()) if finite.size else math.nan,
        }
    return out


def summary(agent_name: str, episodes: Sequence[Mapping[str, float]], **kwargs: Any) -> dict[str, Any]:
    """The JSON object of one agent: ``{"agent", "episodes", "metrics"}``."""
    return {"agent": agent_name, "episodes": len(episodes), "metrics": aggregate(episodes, **kwargs)}
