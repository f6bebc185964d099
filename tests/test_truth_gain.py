"""Belief beside truth: the env's ``info["truth_gain"]`` (the drop of the seen landmarks' squared error, from the
compiled step metrics) against numpy, its sum over an episode, and the evaluation's correlation of it with the
information gain on cases with known answers."""

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


@pytest.mark.parametrize(
    "overrides",
    [{}, {"filter": {"association": "nearest"}, "sensor": {"clutter_rate": 0.5, "detection_prob": 0.9}}],
    ids=["known", "nearest-clutter"],
)
def test_truth_gain_is_the_drop_of_the_squared_errors_of_landmarks_seen_before(overrides):
    env = EKFSLAMEnv(max_episode_steps=300, **overrides)
    _, info = env.reset(seed=5)
    assert info["truth_gain"] == 0.0
    before = _errors(env)
    nonzero = 0
    for action in _held_actions(1, 300):
        _, _, terminated, truncated, info = env.step(action)
        now = _errors(env)
        both = np.isfinite(before) & np.isfinite(now)
        expected = float(np.sum(before[both] - now[both]))
        assert info["truth_gain"] == pytest.approx(expected, rel=0, abs=1e-12)
        nonzero += info["truth_gain"] != 0.0
        before = now
        if terminated or truncated:
            break
    assert nonzero > 100  # the test saw landmarks being corrected, not an empty sum


def test_truth_gains_sum_to_the_first_errors_less_the_final_ones():
    """With known association a seen landmark stays seen, so the gains telescope per landmark: their sum over
    an episode is sum_j (e_j when first seen - e_j at the end), whatever the step at which each was first seen."""
    env = EKFSLAMEnv(max_episode_steps=400)
    env.reset(seed=8)
    first = _errors(env)
    total = 0.0
    for action in _held_actions(2, 400):
        _, _, terminated, truncated, info = env.step(action)
        total += info["truth_gain"]
        now = _errors(env)
        new = np.isnan(first) & np.isfinite(now)
        first[new] = now[new]
        if terminated or truncated:
            break
    seen = np.isfinite(first)
    assert seen.sum() >= 10
    assert total == pytest.approx(float(np.sum(first[seen] - now[seen])), rel=0, abs=1e-9)
    assert total > 0  # the seeded map improved on its first readings


def test_reward_is_unchanged_by_the_truth_gain():
    """The truth gain is information only: the reward's terms stay those of ``reward_terms``."""
    env = EKFSLAMEnv(max_episode_steps=50)
    _, info = env.reset(seed=0)
    for action in _held_actions(3, 50):
        _, reward, _, _, step_info = env.step(action)
        assert "truth_gain" not in step_info["reward_terms"]
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


def test_evaluation_reports_the_correlation_of_the_episodes_gains():
    """run_episode correlates the drops of info["log_det"] with info["truth_gain"], step by step."""
    from ekfslam_gym.evaluation.episodes import make_env, run_episode

    class Held:
        name = "held"

        def reset(self, env, seed=None):
            self.actions, self.t = _held_actions(seed, 200), 0

        def act(self, observation):
            self.t += 1
            return self.actions[self.t - 1]

    env = make_env("EKFSLAM-v0", max_episode_steps=120)
    row = run_episode(env, Held(), 4)
    # The same episode again, its two series recorded here.
    _, info = env.reset(seed=4)
    agent = Held()
    agent.reset(env, seed=4)
    log_det, belief, truth = info["log_det"], [], []
    for _ in range(120):
        _, _, terminated, truncated, info = env.step(agent.act(None))
        belief.append(log_det - info["log_det"])
        truth.append(info["truth_gain"])
        log_det = info["log_det"]
        if terminated or truncated:
            break
    assert (row["gain_pearson"], row["gain_spearman"]) == metrics.gain_correlation(belief, truth)
    assert -1.0 <= row["gain_pearson"] <= 1.0 and -1.0 <= row["gain_spearman"] <= 1.0
