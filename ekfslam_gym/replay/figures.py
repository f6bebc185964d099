"""The figures of a replay on real data, computed once for every data set and printed or written as JSON by the
command line: NIS against its chi^2 band, time per step, landmark errors after alignment to a survey, and the
association counts.

Real data has no pose truth, so NIS (each re-observation's innovation, 2 dof) is the consistency check: its
mean is 2 and 95 % of its values lie in chi2(2).ppf([0.025, 0.975]) = [0.051, 7.38] when the filter's noise
is right; the mean of w consecutive values lies in chi2(2w).ppf([0.025, 0.975]) / w.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .mrclam import ReplaySettings, landmark_errors
from .result import Replay

__all__ = ["nis_band", "nis_summary", "replay_figures", "summarise"]


def nis_band(window: int = 1, dof: int = 2, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided chi^2 band of the mean of ``window`` NIS values of ``dof`` degrees of freedom."""
    from scipy import stats  # here, not at import: scipy.stats costs a second at start-up

    alpha = 1.0 - confidence
    lo, hi = stats.chi2.ppf([alpha / 2, 1 - alpha / 2], dof * window) / window
    return float(lo), float(hi)


def nis_summary(nis: np.ndarray, window: int = 50) -> dict[str, float]:
    """Mean NIS, the fraction of single values inside their 95 % band, and of ``window``-long means inside
    theirs (non-overlapping windows)."""
    nis = np.asarray(nis, dtype=float)
    lo, hi = nis_band(1)
    blocks = nis[: len(nis) // window * window].reshape(-1, window).mean(axis=1)
    wlo, whi = nis_band(window)
    return {
        "readings": int(len(nis)),
        "mean": float(nis.mean()) if len(nis) else float("nan"),
        "inside": float(np.mean((nis >= lo) & (nis <= hi))) if len(nis) else float("nan"),
        "window": window,
        "windows_inside": float(np.mean((blocks >= wlo) & (blocks <= whi))) if len(blocks) else float("nan"),
    }


def replay_figures(result: Replay, variant: str) -> dict[str, Any]:
    """What every replay reports: the filter variant, the steps, the landmarks mapped, NIS and time per step."""
    return {
        "variant": variant,
        "steps": result.steps,
        "landmarks_mapped": int(result.ekf.observed.sum()),
        "nis": nis_summary(result.nis),
        "seconds": result.seconds,
        "microseconds_per_step": result.microseconds_per_step,
    }


def summarise(
    result: Replay, settings: ReplaySettings, truth_ids: np.ndarray, truth_xy: np.ndarray
) -> dict[str, Any]:
    """A replay of a surveyed drive (MRCLAM): ``replay_figures`` and the settings' choices, the landmark
    errors after alignment (per landmark, median, count within 0.18 m) and the association counts."""
    errors, transform = landmark_errors(result.landmark_estimates(), truth_ids, truth_xy)
    values = np.array(list(errors.values()))
    return {
        **replay_figures(result, settings.filter.variant),
        "association": settings.association.kind,
        "range_std": settings.range_std,
        "bearing_std": settings.bearing_std,
        "landmark_errors": {str(k): v for k, v in sorted(errors.items())},
        "median_error": float(np.median(values)) if len(values) else None,
        "within_0.18": int(np.sum(values <= 0.18)),
        "landmarks_mapped": len(values),
        "false_associations": result.false_associations,
        "missed_associations": result.missed_associations,
        "new_landmarks": result.new_landmarks,
        "alignment": {"angle": transform.angle, "translation": transform.translation.tolist()},
    }
