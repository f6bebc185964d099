"""Noise fitted to a real drive by maximum likelihood of the filter's innovations.

Without pose truth the only reference is the readings themselves: a filter whose noise is right predicts each
re-observation with the covariance S it reports. The prediction-error decomposition of the likelihood (Schweppe,
"Evaluation of likelihood functions for Gaussian signals", IEEE T-IT 11(1), 1965) makes this a number to
maximise over the noise parameters:

    log p(z_1..T | theta) = sum_t log N(nu_t; 0, S_t(theta))

with nu_t and S_t the innovations and their covariances of a filter run with theta (``mrclam.replay_drive``
sums it). The landmarks' first readings initialise them and carry no innovation. The search is Nelder-Mead on
the logarithms of the standard deviations (positive, and of very different scales).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .mrclam import Drive, IncrementNoise, ReplaySettings, replay_drive

__all__ = ["FITTED_PARAMETERS", "NoiseFit", "fit_noise", "with_parameters"]

# (name, where it lives): the reading noise in ReplaySettings, the odometry noise in its IncrementNoise
FITTED_PARAMETERS = ("range_std", "bearing_std", "distance", "turn", "drift")


@dataclass(frozen=True)
class NoiseFit:
    """The fitted settings, their log-likelihood, and the search's count of filter runs."""

    settings: ReplaySettings
    log_likelihood: float
    start_log_likelihood: float
    evaluations: int

    def parameters(self) -> dict[str, float]:
        """The fitted standard deviations by name (``FITTED_PARAMETERS``)."""
        return {name: _get(self.settings, name) for name in FITTED_PARAMETERS}


def _get(settings: ReplaySettings, name: str) -> float:
    if hasattr(settings.odometry, name):
        return float(getattr(settings.odometry, name))
    return float(getattr(settings, name))


def with_parameters(settings: ReplaySettings, values: dict[str, float]) -> ReplaySettings:
    """``settings`` with the named standard deviations replaced (reading noise or odometry noise)."""
    odometry = {k: v for k, v in values.items() if hasattr(settings.odometry, k)}
    reading = {k: v for k, v in values.items() if k not in odometry}
    noise: IncrementNoise = dataclasses.replace(settings.odometry, **odometry)
    return dataclasses.replace(settings, odometry=noise, **reading)


def fit_noise(
    drive: Drive,
    landmark_ids: np.ndarray,
    start: ReplaySettings | None = None,
    *,
    names: tuple[str, ...] = FITTED_PARAMETERS,
    max_evaluations: int = 120,
    tolerance: float = 0.5,
) -> NoiseFit:
    """Maximise the innovation log-likelihood of ``drive`` over the standard deviations ``names``, from
    ``start`` (default ``ReplaySettings()``): Nelder-Mead in log space, at most ``max_evaluations`` filter runs,
    stopping when the simplex's log-likelihoods agree within ``tolerance`` nats."""
    from scipy.optimize import minimize

    start = ReplaySettings() if start is None else start
    x0 = np.log([_get(start, name) for name in names])
    runs = [0]

    def cost(x: np.ndarray) -> float:
        runs[0] += 1
        settings = with_parameters(start, dict(zip(names, np.exp(x).tolist(), strict=True)))
        try:
            return -replay_drive(drive, landmark_ids, settings).log_likelihood
        except (np.linalg.LinAlgError, ValueError, RuntimeError):
            return np.inf  # a setting that breaks the filter is not the maximum

    start_value = cost(x0)
    result = minimize(
        cost, x0, method="Nelder-Mead",
        options={"maxfev": max_evaluations, "fatol": tolerance, "xatol": 1e-2, "initial_simplex": None},
    )  # fmt: skip
    fitted = with_parameters(start, dict(zip(names, np.exp(result.x).tolist(), strict=True)))
    return NoiseFit(fitted, -float(result.fun), -start_value, runs[0])
