"""The filter inside the env: pose ANEES, readings and walls, filter failure, covariance over 100k steps."""

import numpy as np
import pytest
from scipy import stats

from ekfslam_gym.envs import EKFSLAMEnv


def test_pose_anees_under_random_driving_is_consistent():
    """50 seeded random drives: the simulator's odometry noise and the filter's motion noise agree."""
    runs, steps = 50, 200
    nees = np.zeros((runs, steps))
    for run in range(runs):
        env = EKFSLAMEnv(max_episode_steps=steps)
        env.reset(seed=100 + run)
        rng = np.random.default_rng(run)
        action = rng.uniform(-1, 1, 2)
        for t in range(steps):
            if t % 10 == 0:
                action = rng.uniform(-1, 1, 2)
            *_, info = env.step(action)
            nees[run, t] = info["pose_nees"]
    anees = nees.mean(axis=0)
    low, high = stats.chi2.ppf([0.025, 0.975], 3 * runs) / runs
    inside = np.mean((anees >= low) & (anees <= high))
    assert inside >= 0.75, f"{inside:.0%} of steps inside [{low:.2f}, {high:.2f}], mean {anees.mean():.2f}"
    assert 2.4 <= anees.mean() <= 3.6


def test_readings_never_cross_a_wall():
    from ekfslam_gym.sim.geometry import segment_blocked

    env = EKFSLAMEnv(world={"layout": "rooms"})
    env.reset(seed=3)
    rng = np.random.default_rng(0)
    layout = env.world.layout
    count = 0
    for _ in range(300):
        *_, info = env.step(rng.uniform(-1, 1, 2))
        x, y, _ = info["true_pose"]
        for j in info["readings"].ids:
            lx, ly = layout.landmarks[j]
            assert not segment_blocked(x, y, lx, ly, layout.walls, layout.wall_radius)
            count += 1
    assert count > 50


def test_filter_failure_terminates_without_raising(monkeypatch):
    """The filter signals a numerical failure with ``FilterDivergedError`` (its public contract: an innovation
    covariance or Sigma that loses positive definiteness raises it); the env ends the episode and reports it
    instead of raising."""
    from ekfslam_gym.filter.ekf import FilterDivergedError

    env = EKFSLAMEnv()
    env.reset(seed=0)

    def diverge(*args, **kwargs):
        raise FilterDivergedError("innovation covariance is not positive definite")

    monkeypatch.setattr(env.filter, "update", diverge)
    _, reward, terminated, truncated, info = env.step(np.zeros(2))
    assert terminated and not truncated and info["filter_failed"] and reward == 0.0
    assert all(value == 0.0 for value in info["reward_terms"].values())


@pytest.mark.slow
def test_covariance_stays_symmetric_positive_definite_over_100k_random_steps():
    env = EKFSLAMEnv(max_episode_steps=100_000, done_std=0.0)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (100_000, 2))
    for t, action in enumerate(actions):
        _, _, terminated, truncated, info = env.step(action)
        assert not info["filter_failed"]
        if t % 20_000 == 0 or t == len(actions) - 1:
            cov = env.filter.cov
            assert np.array_equal(cov, cov.T)
            assert np.all(np.isfinite(cov)) and np.linalg.eigvalsh(cov)[0] > 0
            assert info["log_det"] == pytest.approx(
                np.linalg.slogdet(cov)[1], abs=1e-8 * max(1, abs(info["log_det"]))
            )
    assert truncated
