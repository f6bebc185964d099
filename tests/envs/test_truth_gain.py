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
        terms = step_info["reward_terms"]
        assert reward == terms["info_gain"] + terms["collision"]  # the default weights, 1 and 1


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
    """The optional ``pose_variance`` term, -tr Sigma_xy of the pose estimate after each control step, costs weight x it
    (read against ``info["pose_cov"]`` and the filter's own covariance), the rest of the reward is unchanged,
    and the cost grows while the robot explores without re-observing (dead reckoning between sightings)."""
    weight = 7.0
    costs = []
    for shaped, reward, reward_plain, info in _beside_plain(
        {"pose_variance": weight}, 60, seed=3, action_seed=8
    ):
        term = info["reward_terms"]["pose_variance"]  # unweighted
        cov = np.asarray(shaped.filter.cov)
        assert term == -(cov[0, 0] + cov[1, 1])
        assert term == -(info["pose_cov"][0, 0] + info["pose_cov"][1, 1])
        assert reward == pytest.approx(reward_plain + weight * term, rel=0, abs=1e-9)
        costs.append(term)
    assert all(c < 0.0 for c in costs) and min(costs) < costs[0]  # a variance, and it grows somewhere
