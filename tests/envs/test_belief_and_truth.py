"""docs/belief-and-truth.md against the env: the info-key table is the keys reset and step return, the page's code
runs, the first step's reward is the log-det change the page explains, and a macro step whose filter fails
partway keeps its earlier control steps' rewards."""

from __future__ import annotations

import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401  (registers the ids)
from ekfslam_gym.envs import EKFSLAMEnv
from ekfslam_gym.envs.info import INFO_KEYS, info_keys
from ekfslam_gym.envs.rewards import REWARD_NAMES
from ekfslam_gym.filter.ekf import FilterDivergedError
from ekfslam_gym.filter.models import wheel_motion

PAGE = Path(__file__).resolve().parents[2] / "docs" / "belief-and-truth.md"


@pytest.mark.parametrize(
    "action, macro",
    [
        ({}, False),
        ({"kind": "velocity", "hold": 5}, True),
        ({"kind": "primitives"}, True),
        ({"kind": "waypoint"}, True),
    ],
)
def test_the_info_key_table_is_the_keys_reset_and_step_return(action, macro):
    env = EKFSLAMEnv(action=action, max_episode_steps=5)
    _, info = env.reset(seed=0)
    assert tuple(info) == info_keys(macro=False)
    _, _, _, _, info = env.step(env.action_space.sample())
    assert tuple(info) == info_keys(macro)
    assert tuple(info["reward_terms"]) == REWARD_NAMES


def test_every_info_key_is_named_once_with_its_source():
    names = [key.name for key in INFO_KEYS]
    assert len(names) == len(set(names))
    assert {key.source for key in INFO_KEYS} <= {"belief", "truth", "both", "episode"}
    assert all(key.unit and key.meaning for key in INFO_KEYS)


def test_the_pages_code_runs(capsys):
    blocks = re.findall(r"```python\n(.*?)```", PAGE.read_text(), flags=re.S)
    assert len(blocks) >= 2
    for block in blocks:
        exec(compile(block, str(PAGE), "exec"), {})
    assert capsys.readouterr().out


def _first_prediction(env: gym.Env, sigma_0: np.ndarray, pose_0: np.ndarray, info: dict) -> np.ndarray:
    """Sigma_1 = F Sigma_0 F^T + Q of the filter's first prediction, from the wheel motion model's Jacobians
    at the first odometry reading: F the identity but for the pose block G, Q zero but for V M V^T."""
    wheel_base = env.unwrapped.world.wheel_noise.wheel_base
    _, G, V = wheel_motion(pose_0, *info["odometry"], wheel_base)
    F = np.eye(len(sigma_0))
    F[:3, :3] = G
    Q = np.zeros_like(sigma_0)
    Q[:3, :3] = V @ info["odometry_cov"] @ V.T
    return F @ sigma_0 @ F.T + Q


def test_the_first_reward_is_the_log_det_change_of_the_prior_and_the_first_prediction():
    """With nothing in range (sensor.max_range 2, seed 3) the first control step is a prediction alone: its
    reward is log det Sigma_0 - log det Sigma_1 with Sigma_0 the prior (the pose at filter.pose_prior) and
    Sigma_1 the prediction, about -15 nats standing still, as docs/belief-and-truth.md explains."""
    env = gym.make("EKFSLAM-v0", sensor={"max_range": 2.0})
    _, info = env.reset(seed=3)
    ekf = env.unwrapped.filter
    assert info["landmarks_seen"] == 0
    sigma_0, pose_0 = np.array(ekf.cov), np.array(ekf.pose)
    prior = env.unwrapped.config.filter.pose_prior
    np.testing.assert_array_equal(sigma_0[:3, :3], prior * np.eye(3))
    _, reward, *_, info = env.step(np.zeros(2, dtype=np.float32))
    sigma_1 = _first_prediction(env, sigma_0, pose_0, info)
    expected = np.linalg.slogdet(sigma_0)[1] - np.linalg.slogdet(sigma_1)[1]
    assert reward == pytest.approx(expected, rel=1e-9)
    assert -16.0 < reward < -14.0


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_the_first_reward_is_that_prediction_less_what_the_first_correction_recovers(seed):
    """On EKFSLAM-v0 the same prediction costs about 15 nats and the correction in the same step, re-observing
    the landmarks in view, recovers some: the first reward, standing still, lies between; the second is far smaller."""
    env = gym.make("EKFSLAM-v0")
    env.reset(seed=seed)
    ekf = env.unwrapped.filter
    sigma_0, pose_0 = np.array(ekf.cov), np.array(ekf.pose)
    _, reward, *_, info = env.step(np.zeros(2, dtype=np.float32))
    predicted = _first_prediction(env, sigma_0, pose_0, info)
    prediction = np.linalg.slogdet(sigma_0)[1] - np.linalg.slogdet(predicted)[1]
    correction = np.linalg.slogdet(predicted)[1] - info["log_det"]
    assert -16.0 < prediction < -14.0
    assert correction > 0.0 and reward == pytest.approx(prediction + correction, abs=1e-6)
    _, second, *_ = env.step(np.zeros(2, dtype=np.float32))
    assert abs(second) < 0.5 * abs(reward)


def test_a_macro_step_keeps_the_rewards_of_the_control_steps_before_a_filter_failure(monkeypatch):
    """The filter fails on the third control step of a primitive: the step is terminated with filter_failed, and
    its reward and reward terms are those of the first two control steps (replayed one by one beside it)."""
    macro = EKFSLAMEnv(action={"kind": "primitives"}, reward={"step_cost": 0.5})
    single = EKFSLAMEnv(reward={"step_cost": 0.5})
    macro.reset(seed=4)
    single.reset(seed=4)
    update = macro._filter_update
    calls = []

    def failing_on_the_third(odometry, readings):
        calls.append(1)
        if len(calls) == 3:
            raise FilterDivergedError("injected")
        return update(odometry, readings)

    monkeypatch.setattr(macro, "_filter_update", failing_on_the_third)
    _, reward, terminated, truncated, info = macro.step(0)
    assert info["filter_failed"] and terminated and not truncated
    assert info["inner_steps"] == 3
    rewards, terms = [], dict.fromkeys(REWARD_NAMES, 0.0)
    for command in info["inner_actions"][:2]:
        _, r, *_, single_info = single.step(command)
        rewards.append(r)
        for name, value in single_info["reward_terms"].items():
            terms[name] += value
    assert reward == rewards[0] + rewards[1] != 0.0
    assert info["reward_terms"] == terms and terms["step_cost"] == -2.0
