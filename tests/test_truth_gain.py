"""Belief beside truth: the env's ``info["truth_gain"]`` (the drop of the seen landmarks' squared error, from the
compiled step metrics) and ``info["belief_gain"]`` (the drop of their position variances) against numpy, their
sums over an episode, and the evaluation's correlation of the two and final map NEES on cases with known
answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from ekfslam_gym.envs import EKFSLAMEnv
from ekfslam_gym.evaluation import metrics


def _held_actions(seed: int, n: int) -> np.ndarray:
    """Random actions held for 10 steps (the tests' usual driving)."""
    rng = np.random.default_rng(seed)
    return np.repeat(rng.uniform(-1, 1, (n // 10 + 1, 2)), 10, axis=0)[:n].astype(np.float32)


def _errors(env: EKFSLAMEnv) -> np.ndarray:
    """Each slot's squared position error against the landmark it holds; NaN for slots that hold none."""
    ekf = env.filter
    truth = np.asarray(env.slot_truth)
    held = np.asarray(ekf.observed) & (truth >= 0)
    true = np.asarray(env.true_landmarks)[np.maximum(truth, 0)]
    errors = np.sum((np.asarray(ekf.landmarks) - true) ** 2, axis=1)
    return np.where(held, errors, np.nan)


def _traces(env: EKFSLAMEnv) -> np.ndarray:
    """Each slot's tr Sigma_jj (its 2x2 marginal position covariance), over the same slots as ``_errors``."""
    ekf = env.filter
    held = np.asarray(ekf.observed) & (np.asarray(env.slot_truth) >= 0)
    diagonal = np.diag(np.asarray(ekf.cov))[3:].reshape(-1, 2)
    return np.where(held, diagonal.sum(axis=1), np.nan)


@pytest.mark.parametrize(
    "overrides",
    [{}, {"filter": {"association": "nearest"}, "sensor": {"clutter_rate": 0.5, "detection_prob": 0.9}}],
    ids=["known", "nearest-clutter"],
)
def test_truth_and_belief_gains_are_the_drops_over_the_landmarks_seen_before(overrides):
    """The truth gain drops the squared errors, the belief gain the traces tr Sigma_jj, both over the slots
    that held a landmark before and after the step (the same set)."""
    env = EKFSLAMEnv(max_episode_steps=300, **overrides)
    _, info = env.reset(seed=5)
    assert info["truth_gain"] == 0.0 and info["belief_gain"] == 0.0
    before, traces_before = _errors(env), _traces(env)
    nonzero = 0
    for action in _held_actions(1, 300):
        _, _, terminated, truncated, info = env.step(action)
        now, traces = _errors(env), _traces(env)
        both = np.isfinite(before) & np.isfinite(now)
        assert np.array_equal(both, np.isfinite(traces_before) & np.isfinite(traces))
        expected = float(np.sum(before[both] - now[both]))
        assert info["truth_gain"] == pytest.approx(expected, rel=0, abs=1e-12)
        expected = float(np.sum(traces_before[both] - traces[both]))
        assert info["belief_gain"] == pytest.approx(expected, rel=0, abs=1e-12)
        nonzero += info["truth_gain"] != 0.0 and info["belief_gain"] != 0.0
        before, traces_before = now, traces
        if terminated or truncated:
            break
    assert nonzero > 100  # the test saw landmarks being corrected, not an empty sum


def test_truth_and_belief_gains_sum_to_the_first_values_less_the_final_ones():
    """With known association a seen landmark stays seen, so the gains telescope per landmark: over an episode
    the truth gains sum to sum_j (e_j when first seen - e_j at the end), and the belief gains to
    sum_j (tr Sigma_jj when first seen - tr Sigma_jj at the end), whatever the step at which each was first seen."""
    env = EKFSLAMEnv(max_episode_steps=400)
    env.reset(seed=8)
    first, first_traces = _errors(env), _traces(env)
    total, belief = 0.0, 0.0
    for action in _held_actions(2, 400):
        _, _, terminated, truncated, info = env.step(action)
        total += info["truth_gain"]
        belief += info["belief_gain"]
        now, traces = _errors(env), _traces(env)
        new = np.isnan(first) & np.isfinite(now)
        first[new], first_traces[new] = now[new], traces[new]
        if terminated or truncated:
            break
    seen = np.isfinite(first)
    assert seen.sum() >= 10
    assert total == pytest.approx(float(np.sum(first[seen] - now[seen])), rel=0, abs=1e-9)
    assert belief == pytest.approx(float(np.sum(first_traces[seen] - traces[seen])), rel=0, abs=1e-9)
    assert total > 0 and belief > 0  # the seeded map improved on its first readings, and the filter knows it


def test_belief_gain_is_zero_on_a_failed_step():
    env = EKFSLAMEnv()
    env.reset(seed=0)
    env.filter._cov[:] = -np.eye(env.filter.state_size)
    env.filter._tracking = True
    *_, info = env.step(np.zeros(2))
    assert info["filter_failed"] and info["belief_gain"] == 0.0 and info["truth_gain"] == 0.0


def test_reward_is_unchanged_by_the_truth_and_belief_gains():
    """The truth and belief gains are information only: the reward's terms stay those of ``reward_terms``."""
    env = EKFSLAMEnv(max_episode_steps=50)
    _, info = env.reset(seed=0)
    for action in _held_actions(3, 50):
        _, reward, _, _, step_info = env.step(action)
        assert (
            "truth_gain" not in step_info["reward_terms"] and "belief_gain" not in step_info["reward_terms"]
        )
        assert reward == sum(step_info["reward_terms"].values(), 0.0)


def test_gain_correlation_known_answers():
    rng = np.random.default_rng(0)
    x = rng.normal(size=200)
    assert metrics.gain_correlation(x, 2.5 * x) == pytest.approx((1.0, 1.0), abs=1e-12)
    assert metrics.gain_correlation(x, -0.5 * x + 3.0) == pytest.approx((-1.0, -1.0), abs=1e-12)
    pearson, spearman = metrics.gain_correlation(x, np.exp(3 * x))  # monotone, not linear
    assert spearman == pytest.approx(1.0, abs=1e-12) and pearson < 0.9
    y = 0.3 * x + rng.normal(size=200)
    y[[3, 7]] = y[5]  # ties
    pearson, spearman = metrics.gain_correlation(x, y)
    assert pearson == pytest.approx(stats.pearsonr(x, y)[0], abs=1e-12)
    assert spearman == pytest.approx(stats.spearmanr(x, y)[0], abs=1e-12)
    # Non-finite steps are left out; too few steps or a constant series is undefined.
    x_nan, y_nan = np.append(x, np.nan), np.append(y, 1.0)
    assert metrics.gain_correlation(x_nan, y_nan) == pytest.approx((pearson, spearman), abs=1e-12)
    assert all(math.isnan(v) for v in metrics.gain_correlation(x, np.zeros_like(x)))
    assert all(math.isnan(v) for v in metrics.gain_correlation([1.0, 2.0], [1.0, 3.0]))
    with pytest.raises(ValueError, match="equally long"):
        metrics.gain_correlation(x, x[:-1])


@pytest.mark.parametrize(
    "overrides",
    [{}, {"filter": {"association": "nearest"}, "sensor": {"clutter_rate": 0.5, "detection_prob": 0.9}}],
    ids=["known", "nearest-clutter"],
)
def test_evaluation_reports_the_belief_truth_correlation_and_the_final_map_nees(overrides):
    """run_episode correlates info["belief_gain"] with info["truth_gain"], step by step, and scores the final
    map: the joint NEES of the slots holding a landmark, over its 2 n dof."""
    from ekfslam_gym.evaluation.episode_metrics import BELIEF_KEYS, METRIC_KEYS
    from ekfslam_gym.evaluation.rollout import make_env, run_episode

    class Held:
        name = "held"

        def reset(self, env, seed=None):
            self.actions, self.t = _held_actions(seed, 200), 0

        def act(self, observation):
            self.t += 1
            return self.actions[self.t - 1]

    assert set(BELIEF_KEYS) <= set(METRIC_KEYS)
    env = make_env("EKFSLAM-v0", overrides, max_episode_steps=120)
    row = run_episode(env, Held(), 4)
    # The same episode again, its two series recorded here.
    env.reset(seed=4)
    agent = Held()
    agent.reset(env, seed=4)
    belief, truth = [], []
    for _ in range(120):
        _, _, terminated, truncated, info = env.step(agent.act(None))
        belief.append(info["belief_gain"])
        truth.append(info["truth_gain"])
        if terminated or truncated:
            break
    expected = metrics.gain_correlation(belief, truth)
    assert (row["belief_truth_pearson"], row["belief_truth_spearman"]) == expected
    assert 0.0 < row["belief_truth_pearson"] <= 1.0 and -1.0 <= row["belief_truth_spearman"] <= 1.0
    u = env.unwrapped
    slots = np.flatnonzero(np.isfinite(_errors(u)))
    index = (3 + 2 * slots[:, None] + np.arange(2)).ravel()
    error = np.asarray(u.filter.mean)[index] - u.true_landmarks[np.asarray(u.slot_truth)[slots]].ravel()
    nees = error @ np.linalg.inv(np.asarray(u.filter.cov)[np.ix_(index, index)]) @ error
    assert row["map_nees"] == pytest.approx(nees / index.size, rel=1e-9)


def _beside_plain(reward: dict, steps: int, seed: int, action_seed: int, **kwargs):
    """Steps an env with ``reward`` beside one with the default reward, on the same seeded random velocity
    commands, until the episode ends; yields (the shaped env, its reward, the plain env's reward, its info)."""
    plain = EKFSLAMEnv(max_episode_steps=steps, **kwargs)
    shaped = EKFSLAMEnv(max_episode_steps=steps, reward=reward, **kwargs)
    plain.reset(seed=seed)
    shaped.reset(seed=seed)
    rng = np.random.default_rng(action_seed)
    for _ in range(steps):
        a = rng.uniform(-1, 1, 2).astype(np.float32)
        _, reward_plain, *_ = plain.step(a)
        _, shaped_reward, terminated, truncated, info = shaped.step(a)
        yield shaped, shaped_reward, reward_plain, info
        if terminated or truncated:
            return


def test_pose_variance_reward_is_minus_its_weight_times_the_pose_position_variance():
    """The optional ``pose_variance`` term costs weight x tr Sigma_xy of the pose estimate after each control step
    (read against ``info["pose_cov"]`` and the filter's own covariance), the rest of the reward is unchanged,
    and the cost grows while the robot explores without re-observing (dead reckoning between sightings)."""
    weight = 7.0
    costs = []
    for shaped, reward, reward_plain, info in _beside_plain(
        {"pose_variance": weight}, 60, seed=3, action_seed=8
    ):
        term = info["reward_terms"]["pose_variance"]
        cov = np.asarray(shaped.filter.cov)
        assert term == -weight * (cov[0, 0] + cov[1, 1])
        assert term == -weight * (info["pose_cov"][0, 0] + info["pose_cov"][1, 1])
        assert reward == pytest.approx(reward_plain + term, rel=0, abs=1e-9)
        costs.append(term)
    assert all(c < 0.0 for c in costs) and min(costs) < costs[0]  # a variance, and it grows somewhere


@pytest.mark.parametrize("filter_", [{}, {"association": "nearest"}], ids=["known", "unknown"])
def test_pose_error_reward_is_minus_its_weight_times_the_true_squared_position_error(filter_):
    """The optional ``pose_error`` term costs weight x |(x, y) estimate - true|^2 after each control step (read
    against the filter's mean and ``info["true_pose"]``), the rest of the reward is unchanged, and it is not the
    variance term: the error and the variance differ step by step."""
    weight = 3.0
    ratios = []
    stepped = _beside_plain({"pose_error": weight}, 80, seed=6, action_seed=9, filter=filter_)
    for shaped, reward, reward_plain, info in stepped:
        term = info["reward_terms"]["pose_error"]
        error = np.asarray(shaped.filter.mean)[:2] - np.asarray(info["true_pose"])[:2]
        assert term == pytest.approx(-weight * float(error @ error), rel=1e-12, abs=1e-15)
        assert reward == pytest.approx(reward_plain + term, rel=0, abs=1e-9)
        cov = np.asarray(shaped.filter.cov)
        ratios.append(-term / weight / (cov[0, 0] + cov[1, 1]))
    assert all(r >= 0.0 for r in ratios) and max(ratios) - min(ratios) > 0.1


def _log_rms_std(env: EKFSLAMEnv) -> float:
    """ln sqrt(mean tr Sigma_jj) over the slots the filter holds a landmark in, from its covariance; NaN if none."""
    cov = np.asarray(env.filter.cov)
    seen = np.flatnonzero(np.isfinite(_errors(env)))
    if seen.size == 0:
        return math.nan
    traces = cov[3 + 2 * seen, 3 + 2 * seen] + cov[4 + 2 * seen, 4 + 2 * seen]
    return 0.5 * math.log(traces.mean())


def _telescoping_term(name, weight, measure, steps, seed, check=None, **kwargs):
    """Steps an env paying ``name`` at ``weight`` beside one with the default reward, on the tests' held random
    velocity commands (seeded random primitives in a macro env), until the episode ends, and checks that the term
    is 0 while ``measure(env)`` is NaN (nothing seen yet), weight x its drop over each control step, and the only
    change to the reward; ``check(info, now, term)`` adds a test of each step. Returns the episode's terms and
    the measure at reset, at its first finite value and at the end."""
    macro = "action" in kwargs
    plain = EKFSLAMEnv(max_episode_steps=steps, **kwargs)
    shaped = EKFSLAMEnv(max_episode_steps=steps, reward={name: weight}, **kwargs)
    plain.reset(seed=seed)
    shaped.reset(seed=seed)
    at_reset = first = previous = measure(shaped)
    rng = np.random.default_rng(6)
    terms = []
    for a in _held_actions(2, steps):
        if macro:
            a = int(rng.integers(9))
        _, reward_plain, *_ = plain.step(a)
        _, reward, terminated, truncated, info = shaped.step(a)
        term = info["reward_terms"][name]
        now = measure(shaped)
        if check is not None:
            check(info, now, term)
        if math.isnan(previous):
            first = now
            if not macro:  # a macro step's terms also hold its inner steps after the first landmark
                assert term == 0.0
        elif not macro:
            assert term == pytest.approx(weight * (previous - now), rel=1e-9, abs=1e-12)
        assert reward == pytest.approx(reward_plain + term, rel=0, abs=1e-9)
        previous = now
        terms.append(term)
        if terminated or truncated:
            break
    return terms, at_reset, first, previous


@pytest.mark.parametrize("filter_", [{}, {"association": "nearest"}], ids=["known", "unknown"])
def test_map_accuracy_reward_telescopes_to_the_log_ratio_of_the_expected_landmark_rmse(filter_):
    """The optional ``map_accuracy`` term pays weight x the drop of ln sqrt(mean_j tr Sigma_jj) over the seen
    landmarks (read against the filter's covariance), 0 until a landmark is seen, the rest of the reward is
    unchanged, and over an episode the terms sum to weight x ln(R_first / R_final); a discovery placed less
    certainly than the map so far costs, re-observations pay."""
    weight = 30.0
    terms, _, first, last = _telescoping_term("map_accuracy", weight, _log_rms_std, 120, 5, filter=filter_)
    assert sum(terms) == pytest.approx(weight * (first - last), rel=1e-9, abs=1e-9)
    assert min(terms) < 0.0 < max(terms)  # both a costly discovery and a paying re-observation happened


def _mse(env: EKFSLAMEnv) -> float:
    """The mean squared position error over the slots holding a landmark, from the filter and the truth; NaN if none."""
    errors = _errors(env)
    return float(np.nanmean(errors)) if np.isfinite(errors).any() else math.nan


def _mse_is_the_squared_map_rmse(info: dict, now: float, term: float) -> None:
    if math.isnan(now):
        assert info["landmarks_seen"] == 0 and term == 0.0
    else:
        assert now == pytest.approx(info["map_rmse"] ** 2, rel=1e-9, abs=1e-15)


@pytest.mark.parametrize(
    "kwargs, seed",
    [
        ({}, 5),
        ({"filter": {"association": "nearest"}}, 5),
        ({"action": {"kind": "primitives", "hold": 10}}, 5),
        ({"sensor": {"max_range": 2.0}}, 3),  # nothing in range at reset: the first landmark comes at step 25
    ],
    ids=["known", "unknown", "primitives", "none-seen-at-reset"],
)
def test_map_error_reward_telescopes_to_the_drop_of_the_true_mean_squared_landmark_error(kwargs, seed):
    """The optional ``map_error`` term pays weight x the drop of the seen landmarks' true mean squared position
    error (read against the filter's landmarks and the true ones, and against ``info["map_rmse"]``), 0 until a
    landmark is seen, the rest of the reward is unchanged, and over an episode the terms sum to weight x
    (MSE_first - MSE_final), in a macro step too (summed over its inner steps); a discovery placed worse than
    the map so far costs, a correction pays."""
    weight = 5000.0
    steps = 30 if "action" in kwargs else 150
    check = _mse_is_the_squared_map_rmse
    terms, at_reset, first, last = _telescoping_term("map_error", weight, _mse, steps, seed, check, **kwargs)
    assert math.isnan(at_reset) == (seed == 3)
    assert sum(terms) == pytest.approx(weight * (first - last), rel=1e-9, abs=1e-9)
    assert min(terms) < 0.0 < max(terms)  # both a costly discovery and a paying correction happened


@pytest.mark.parametrize("action", [{}, {"action": {"kind": "primitives", "hold": 10}}])
def test_map_variance_reward_is_its_weight_times_the_belief_gain(action):
    """The optional ``map_variance`` term pays weight x ``info["belief_gain"]`` (summed over a macro step's inner
    steps), the rest of the reward is unchanged, and over an episode of control steps it sums to weight x
    (each seen landmark's tr Sigma_jj at first sight - its final one): nothing for discoveries, the drop of the
    mapped part's variance for everything after."""
    weight = 40.0
    plain = EKFSLAMEnv(max_episode_steps=30, **action)
    shaped = EKFSLAMEnv(max_episode_steps=30, reward={"map_variance": weight}, **action)
    plain.reset(seed=4)
    _, info = shaped.reset(seed=4)
    assert "map_variance" not in info["reward_terms"]
    first = _traces(shaped)  # NaN for the landmarks not yet seen
    rng = np.random.default_rng(5)
    total, nonzero = 0.0, 0
    for _ in range(30):
        a = int(rng.integers(9)) if action else rng.uniform(-1, 1, 2).astype(np.float32)
        _, reward_plain, *_, info_plain = plain.step(a)
        _, reward, terminated, truncated, info = shaped.step(a)
        term = info["reward_terms"]["map_variance"]
        assert term == pytest.approx(weight * info["belief_gain"], rel=1e-12, abs=1e-15)  # sums of products
        assert reward == pytest.approx(reward_plain + term, rel=0, abs=1e-9)
        assert info["belief_gain"] == info_plain["belief_gain"]  # the same drive and filter
        now = _traces(shaped)
        first = np.where(np.isnan(first), now, first)
        total += term
        nonzero += term != 0.0
        if terminated or truncated:
            break
    assert nonzero > 0 and total > 0.0  # marginal variances of seen landmarks only fall in an EKF
    if not action:  # with macro steps a landmark's first sight falls between the observed steps
        assert total == pytest.approx(weight * np.nansum(first - _traces(shaped)), rel=1e-9, abs=1e-12)
