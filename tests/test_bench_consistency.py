"""bench/consistency.py drives the env itself (reset and step) and measures ANEES against its chi-square bounds:
its numbers on a seeded run, and its arithmetic on NEES drawn from the chi-square law."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from ekfslam_gym.evaluation.metrics import nees_bounds

BENCH = Path(__file__).resolve().parents[1] / "bench" / "consistency.py"
RUNS, STEPS = 20, 60


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_consistency", BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("model", ["wheels", "odometry"])
def test_the_env_filter_is_consistent_on_a_seeded_run(bench, model):
    """EKFSLAM-v0 driven forward with a fresh command every step: the ANEES over 20 seeded runs stays inside
    the 95 % bounds at most steps, its median inside them, and no filter fails."""
    found = bench.pose_nees("EKFSLAM-v0", "forward", model, "ekf", RUNS, STEPS)
    bounds = nees_bounds(3, RUNS)
    assert found.nees.shape == (RUNS, STEPS) and found.failed == 0
    assert bounds[0] <= np.median(found.anees) <= bounds[1]
    assert found.inside(bounds) >= 0.75


def test_the_runs_are_the_env_episodes_of_their_seeds(bench):
    """Run r is the env's episode of seed r: the same NEES as stepping the env by hand."""
    import gymnasium as gym

    from ekfslam_gym.evaluation.drivings import driving_actions

    found = bench.pose_nees("EKFSLAM-v0", "random", "wheels", "fej", 2, 15)
    env = gym.make("EKFSLAM-v0", max_episode_steps=15, filter={"motion_model": "wheels", "variant": "fej"})
    env.reset(seed=1)
    robot = env.unwrapped.config.robot
    by_hand = [env.step(a.astype(np.float32))[-1]["pose_nees"]
               for a in driving_actions("random", np.random.default_rng([1, 0]), 15, robot)]  # fmt: skip
    np.testing.assert_array_equal(found.nees[1], by_hand)


def test_the_bounds_count_steps_as_the_chi_square_law_says(bench):
    """NEES drawn from chi2(3) sit inside the bounds at ~95 % of the steps; three times too large, at none."""
    rng = np.random.default_rng(0)
    draws = rng.chisquare(3, size=(RUNS, 400))
    bounds = nees_bounds(3, RUNS)
    consistent = bench.Consistency(draws, np.zeros_like(draws, dtype=bool))
    overconfident = bench.Consistency(3.0 * draws, np.zeros_like(draws, dtype=bool))
    assert 0.9 <= consistent.inside(bounds) <= 0.99
    assert overconfident.inside(bounds) == 0.0
    draws[0, 5] = np.nan
    assert bench.Consistency(draws, np.zeros_like(draws, dtype=bool)).failed == 1
