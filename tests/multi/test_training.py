"""Shared-parameter PPO for the team env: SuperSuit's adapter as SB3 sees it, the recipe's checks, the shipped
team policy (one episode; never its quality) and the results table of docs/multi-robot.md."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pettingzoo")

from ekfslam_gym.multi import parallel_env  # noqa: E402
from ekfslam_gym.multi.evaluation import run_episode  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "models" / "team_ppo_3robots.zip"


def test_vec_env_has_one_env_per_robot_and_is_seeded():
    pytest.importorskip("supersuit")
    pytest.importorskip("stable_baselines3")
    from ekfslam_gym.multi.training import team_vec_env

    def first_observations(seed: int) -> np.ndarray:
        vec = team_vec_env({"n_robots": 3, "max_episode_steps": 4}, n_envs=2, seed=seed)
        return vec.reset()

    observations = first_observations(5)
    assert observations.shape == (6, parallel_env(3).observation_space("robot_0").shape[0])
    np.testing.assert_array_equal(observations, first_observations(5))
    assert not np.array_equal(observations, first_observations(6))
    # team copy k is seeded seed + k: its robots see what a team env reset with that seed shows them
    team_obs, _ = parallel_env(3, max_episode_steps=4).reset(seed=6)
    np.testing.assert_array_equal(observations[3], team_obs["robot_0"])


def test_vec_env_steps_every_robot():
    pytest.importorskip("supersuit")
    pytest.importorskip("stable_baselines3")
    from ekfslam_gym.multi.training import team_vec_env

    vec = team_vec_env({"n_robots": 2, "max_episode_steps": 3}, n_envs=1, seed=0)
    vec.reset()
    for _ in range(3):
        observations, rewards, dones, infos = vec.step(np.array([0, 7]))
    assert observations.shape[0] == 2 and rewards[0] == rewards[1]
    assert dones.all()  # the episode's three steps are done, for both robots at once


def test_recipe_errors_name_the_key(tmp_path):
    from ekfslam_gym.multi.training import read_recipe

    path = tmp_path / "recipe.yaml"
    path.write_text("n_envs: 2\nlearning_rate: 0.1\n")
    with pytest.raises(ValueError, match="learning_rate"):
        read_recipe(path)
    with pytest.raises(FileNotFoundError):
        read_recipe(tmp_path / "missing.yaml")
    assert read_recipe(ROOT / "configs" / "multi" / "ppo_team.yaml")["env_kwargs"] == {"n_robots": 3}


@pytest.mark.parametrize("n_robots", [2, 3])
def test_shipped_team_policy_runs_an_episode(n_robots):
    pytest.importorskip("stable_baselines3")
    from ekfslam_gym.multi.training import TeamPolicy

    policy = TeamPolicy(SHIPPED)
    team = parallel_env(n_robots=n_robots, max_episode_steps=5)
    observations, _ = team.reset(seed=0)
    actions = policy.act(observations)
    assert set(actions) == set(team.agents)
    assert all(team.action_space(a).contains(action) for a, action in actions.items())
    metrics = run_episode(team, policy, seed=1)
    assert np.isfinite(metrics["map_log_det"]) and metrics["time_to_complete"] > 0


def test_docs_results_table_is_current():
    pytest.importorskip("scipy")
    script = ROOT / "docs" / "multi_robot.py"
    assert importlib.util.spec_from_file_location("multi_robot", script) is not None
    result = subprocess.run(
        [sys.executable, str(script), "--check"], cwd=ROOT, capture_output=True, text=True
    )
    assert result.returncode == 0, "docs/multi-robot.md's table is stale: run python docs/multi_robot.py"
