"""The evaluation metrics on cases with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from ekfslam_gym.evaluation import metrics


def test_ate_of_a_shifted_trajectory_is_the_shift():
    rng = np.random.default_rng(0)
    true = np.column_stack([rng.uniform(0, 20, (100, 2)), rng.uniform(-3, 3, 100)])
    estimated = true.copy()
    estimated[:, :2] += [3.0, -4.0]
    estimated[:, 2] += 0.3  # headings do not enter the ATE
    assert metrics.ate(estimated, true) == pytest.approx(5.0, rel=1e-12)
    assert metrics.ate(true, true) == 0.0


def test_ate_is_an_rmse_not_a_mean_error():
    true = np.zeros((4, 2))
    estimated = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [2.0, 0.0]])
    assert metrics.ate(estimated, true) == pytest.approx(1.0)  # sqrt(4 / 4), the mean error would be 0.5


def test_pose_errors_wrap_the_heading():
    errors = metrics.pose_errors(np.array([[0.0, 0.0, 3.1]]), np.array([[1.0, 2.0, -3.1]]))
    assert errors[0, :2] == pytest.approx([1.0, 2.0])
    assert errors[0, 2] == pytest.approx(2 * math.pi - 6.2)


def test_landmark_errors_score_only_seen_landmarks_and_count_the_missed():
    true = np.array([[0.0, 0.0], [5.0, 5.0], [9.0, 1.0], [3.0, 3.0]])
    estimated = true + np.array([[0.3, 0.4], [0.0, 1.0], [100.0, 100.0], [0.0, 0.0]])
    seen = np.array([True, True, False, False])
    rmse, missed = metrics.landmark_errors(estimated, true, seen)
    assert rmse == pytest.approx(math.sqrt((0.25 + 1.0) / 2))
    assert missed == 2
    rmse, missed = metrics.landmark_errors(estimated, true, np.zeros(4, bool))
    assert math.isnan(rmse) and missed == 4


def test_per_step_nees_bounds_are_the_chi2_quantiles():
    lo, hi = metrics.nees_bounds(3, 1)
    assert lo == pytest.approx(0.2158, abs=1e-4)
    assert hi == pytest.approx(9.3484, abs=1e-4)
    lo50, hi50 = metrics.nees_bounds(3, 50)
    assert lo < lo50 < 3.0 < hi50 < hi


def test_the_written_out_step_bounds_are_the_computed_ones():
    """episode_metrics writes the per-step bounds out (no scipy.stats at import): exactly the computed ones."""
    from ekfslam_gym.evaluation.episode_metrics import NEES_STEP_BOUNDS, POSE_DIM

    assert NEES_STEP_BOUNDS == metrics.nees_bounds(POSE_DIM, 1)


@pytest.fixture
def gaussian_case():
    rng = np.random.default_rng(42)
    a = rng.normal(size=(3, 3))
    cov = a @ a.T + 0.1 * np.eye(3)
    n = 4000
    samples = rng.multivariate_normal(np.zeros(3), cov, size=n)
    return samples, np.broadcast_to(cov, (n, 3, 3)).copy()


def test_nees_of_samples_from_the_stated_covariance_is_consistent(gaussian_case):
    errors, covs = gaussian_case
    values = metrics.nees(errors, covs)
    lo, hi = metrics.nees_bounds(3, len(values))
    average = metrics.anees(values)
    margin = 0.2 * (hi - lo)
    assert lo + margin < average < hi - margin
    inside = metrics.fraction_in_bounds(values, metrics.nees_bounds(3, 1))
    assert 0.93 < inside < 0.97


def test_nees_flags_an_overconfident_covariance(gaussian_case):
    errors, covs = gaussian_case
    values = metrics.nees(errors, 0.25 * covs)
    _, hi = metrics.nees_bounds(3, len(values))
    assert metrics.anees(values) > 3.5 * hi


def test_nees_is_nan_for_a_non_definite_covariance_and_nan_counts_outside():
    values = metrics.nees(np.ones((2, 3)), np.stack([np.eye(3), -np.eye(3)]))
    assert values[0] == pytest.approx(3.0) and math.isnan(values[1])
    assert metrics.fraction_in_bounds(values, (0.2, 9.0)) == 0.5
    assert metrics.anees(values) == pytest.approx(3.0)


def test_iqm_of_known_arrays():
    assert metrics.iqm(np.arange(1.0, 9.0)) == pytest.approx(4.5)  # mean of 3, 4, 5, 6
    assert metrics.iqm([7.0] * 5) == 7.0
    robust = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 1e6])
    assert metrics.iqm(robust) == pytest.approx(4.5)
    assert metrics.iqm([1.0, np.nan, 2.0, 3.0, 4.0]) == pytest.approx(2.5)
    assert math.isnan(metrics.iqm([]))
    assert metrics.iqm(np.arange(100.0)) == pytest.approx(stats.trim_mean(np.arange(100.0), 0.25))


def test_bootstrap_ci_contains_the_iqm_is_seeded_and_narrows_with_more_data():
    rng = np.random.default_rng(1)
    small = rng.normal(10.0, 2.0, 20)
    large = rng.normal(10.0, 2.0, 500)
    lo_s, hi_s = metrics.bootstrap_ci(small, seed=3)
    lo_l, hi_l = metrics.bootstrap_ci(large, seed=3)
    assert lo_s <= metrics.iqm(small) <= hi_s
    assert lo_l <= metrics.iqm(large) <= hi_l
    assert hi_l - lo_l < 0.5 * (hi_s - lo_s)
    assert metrics.bootstrap_ci(small, seed=3) == (lo_s, hi_s)
    assert metrics.bootstrap_ci([4.0]) == (4.0, 4.0)
    assert all(math.isnan(v) for v in metrics.bootstrap_ci([np.nan]))
