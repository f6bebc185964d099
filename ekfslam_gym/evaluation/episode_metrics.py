"""The metrics of one finished episode, from its recorded trajectory and the env's final belief.

Metrics of one episode (``METRIC_KEYS``): ``return`` (sum of rewards), ``map_log_det`` (log det of the final map
block Sigma_mm, nats), ``pose_log_det`` (log det of the final marginal pose covariance), ``landmark_rmse`` (m,
final estimates of the seen landmarks), ``missed_landmarks`` (never seen), ``seen_fraction``, ``ate`` (m, RMSE of
estimated vs true positions over the steps, no alignment), ``anees`` (the pose NEES averaged over the steps),
``nees_in_bounds`` (fraction of steps whose pose NEES lies within the per-step 95 % chi-squared bounds, ideally
0.95), ``loop_closures``, ``collisions`` (steps in contact with a wall), ``path_length`` (m, true),
``time_to_complete`` (s of simulated time until the map was first complete, every landmark's sigma below
``done_std``: ``info["time_to_complete"]``; the episode's length when it never was, so that a map never
completed counts as the slowest, not as missing), and belief
beside truth (``BELIEF_KEYS``, one value per episode, aggregated over episodes like every metric: IQM and CI,
not pooled):

- ``belief_truth_pearson`` and ``belief_truth_spearman``: the correlation over the episode's env steps of
  ``info["belief_gain"]`` (the drop of the seen landmarks' position variances, what the filter believes the map
  gained) and ``info["truth_gain"]`` (the drop of their squared errors, what it gained; both m^2 over the same
  landmarks, the env's docstring defines them). Low: the steps the filter believes informative are not those
  that make the map better. The drop of ``info["log_det"]`` (the reward's information gain) is not correlated
  with the truth gain here: its steps are ruled by discoveries (about 20 nats each, while a new landmark's error
  enters the truth gain only from the next step) and by the pose's prediction noise, so its Pearson
  correlation is about 0 for every agent (docs/evaluation.md, "Belief beside truth") and tells none apart: not reported.
- ``map_nees``: the NEES of the seen landmarks' final estimates jointly, e_m^T Sigma_mm^-1 e_m, divided by its
  2 n_seen degrees of freedom (as in ``consistency``): about 1 for a consistent filter, above 1 when the filter
  believes its map better than it is (the over-confidence a reward for believed information pays for). Chosen
  over the ratio sum(belief_gain) / sum(truth_gain), which divides by a noisy sum that can be near 0 or below
  (a map made no better): under consistency the NEES is chi2(2 n_seen) / (2 n_seen), its spread known.

With unknown data association (``filter.association`` not ``known``) also ``ASSOCIATION_KEYS``, the episode's
``false_associations`` and ``missed_associations``, and the map metrics score each filter slot against the
true landmark it holds (``env.slot_truth``): a landmark is missed when no slot holds it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from . import metrics
from .consistency import map_nees

METRIC_KEYS: tuple[str, ...] = (
    "return",
    "map_log_det",
    "pose_log_det",
    "landmark_rmse",
    "missed_landmarks",
    "seen_fraction",
    "ate",
    "anees",
    "nees_in_bounds",
    "loop_closures",
    "collisions",
    "path_length",
    "time_to_complete",
    "belief_truth_pearson",
    "belief_truth_spearman",
    "map_nees",
)

BELIEF_KEYS: tuple[str, ...] = ("belief_truth_pearson", "belief_truth_spearman", "map_nees")
"""Belief beside truth, part of ``METRIC_KEYS`` (the module docstring defines them)."""

ASSOCIATION_KEYS: tuple[str, ...] = ("false_associations", "missed_associations")
"""With unknown data association: the env's counts over the episode (``EKFSLAMEnv``'s docstring)."""

POSE_DIM = 3
# metrics.nees_bounds(POSE_DIM, 1), chi2.ppf([0.025, 0.975], 3), written out so that importing the metrics does
# not import scipy.stats (a second of every command's start-up); tests/evaluation/test_metrics.py holds them equal.
NEES_STEP_BOUNDS = (0.21579528262389797, 9.348403604496148)


def _slogdet(matrix: np.ndarray) -> float:
    if matrix.size == 0:
        return 0.0
    if not np.all(np.isfinite(matrix)):
        return math.nan
    sign, value = np.linalg.slogdet(matrix)
    return float(value) if sign > 0 else math.nan


def time_to_complete(last_info: Mapping[str, Any], dt: float) -> float:
    """s until the map was complete (``info["time_to_complete"]``), or the episode's length if it never was."""
    value = float(last_info.get("time_to_complete", math.inf))
    return value if math.isfinite(value) else float(last_info["step"]) * dt


def episode_metrics(
    env: gym.Env,
    total_return: float,
    true_poses: np.ndarray,
    estimated_poses: np.ndarray,
    step_nees: np.ndarray,
    last_info: Mapping[str, Any],
    belief_gains: np.ndarray,
    truth_gains: np.ndarray,
) -> dict[str, float]:
    """The ``METRIC_KEYS`` of a finished episode from its recorded trajectory, the pose NEES the env reported at
    each step (``info["pose_nees"]``), the per-step belief and truth gains (``info["belief_gain"]``,
    ``info["truth_gain"]``) and the env's final belief."""
    u = env.unwrapped
    ekf = u.filter
    cov = np.asarray(ekf.cov)
    unknown = u.config.filter.association != "known"
    if unknown:
        truth = np.asarray(u.slot_truth)
        held = np.asarray(ekf.observed) & (truth >= 0)
        true_landmarks = u.true_landmarks[np.maximum(truth, 0)]
        rmse, _ = metrics.landmark_errors(np.asarray(ekf.landmarks), true_landmarks, held)
        missed = ekf.n_landmarks - np.unique(truth[held]).size
        seen_fraction = 1.0 - missed / ekf.n_landmarks if ekf.n_landmarks else math.nan
    else:
        held, true_landmarks = np.asarray(ekf.observed), u.true_landmarks
        rmse, missed = metrics.landmark_errors(np.asarray(ekf.landmarks), true_landmarks, held)
        seen_fraction = float(np.mean(ekf.observed)) if ekf.n_landmarks else math.nan
    value, dof = map_nees(np.asarray(ekf.mean), cov, held, true_landmarks)
    result = {
        "return": float(total_return),
        "map_log_det": _slogdet(cov[3:, 3:]),
        "pose_log_det": _slogdet(cov[:3, :3]),
        "landmark_rmse": rmse,
        "missed_landmarks": float(missed),
        "seen_fraction": seen_fraction,
        "ate": metrics.ate(estimated_poses, true_poses),
        "anees": metrics.anees(step_nees),
        "nees_in_bounds": metrics.fraction_in_bounds(step_nees, NEES_STEP_BOUNDS),
        "loop_closures": float(last_info["loop_closures"]),
        "collisions": float(last_info["collisions"]),
        "path_length": float(last_info["path_length"]),
        "time_to_complete": time_to_complete(last_info, u.config.dt),
    }
    pearson, spearman = metrics.gain_correlation(belief_gains, truth_gains)
    result["belief_truth_pearson"], result["belief_truth_spearman"] = pearson, spearman
    result["map_nees"] = value / dof if dof else math.nan
    if unknown:
        result.update({key: float(last_info[key]) for key in ASSOCIATION_KEYS})
    return result
