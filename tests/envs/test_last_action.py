"""``observation.last_action``: the Dict observation's memory of the action the last env step executed (a
one-hot primitive, or the clipped velocity or waypoint goal), zeros after reset, in every action interface;
both checkers pass, and the rest of the observation is unchanged."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401  (registers the envs)
from ekfslam_gym.envs import PRIMITIVES, EKFSLAMEnv

KINDS = [{"kind": "velocity"}, {"kind": "velocity", "hold": 5}, {"kind": "primitives"}, {"kind": "waypoint"}]
DICT = {"kind": "dict", "last_action": True}


def _ids(action):
    return f"{action['kind']}-{action.get('hold')}"


@pytest.mark.parametrize("action", KINDS, ids=_ids)
def test_the_key_holds_the_executed_action_and_zeros_after_reset(action):
    env = gym.make("EKFSLAM-v0", action=action, observation=DICT, max_episode_steps=20)
    space = env.observation_space["last_action"]
    discrete = isinstance(env.action_space, gym.spaces.Discrete)
    assert space.dtype == np.float32
    assert space.shape == ((len(PRIMITIVES),) if discrete else (2,))
    observation, _ = env.reset(seed=3)
    assert np.array_equal(observation["last_action"], np.zeros(space.shape, np.float32))
    env.action_space.seed(3)
    for _ in range(5):
        chosen = env.action_space.sample()
        if not discrete:
            chosen = (1.5 * chosen).astype(np.float32)  # out of bounds: the clipped action is remembered
        observation, *_ = env.step(chosen)
        expected = np.eye(len(PRIMITIVES), dtype=np.float32)[chosen] if discrete else np.clip(chosen, -1, 1)
        assert np.array_equal(observation["last_action"], expected)
        assert space.contains(observation["last_action"])
    observation, _ = env.reset(seed=4)
    assert not observation["last_action"].any()
    env.close()


@pytest.mark.parametrize("action", [KINDS[0], KINDS[2], KINDS[3]], ids=_ids)
def test_the_rest_of_the_observation_is_unchanged(action):
    plain = gym.make("EKFSLAM-v0", action=action, observation={"kind": "dict"}, max_episode_steps=10)
    extra = gym.make("EKFSLAM-v0", action=action, observation=DICT, max_episode_steps=10)
    first, _ = plain.reset(seed=5)
    second, _ = extra.reset(seed=5)
    plain.action_space.seed(5)
    for _ in range(4):
        assert set(second) == set(first) | {"last_action"}
        assert all(np.array_equal(first[key], second[key]) for key in first)
        chosen = plain.action_space.sample()
        first, *_ = plain.step(chosen)
        second, *_ = extra.step(chosen)


@pytest.mark.parametrize("action", KINDS, ids=_ids)
def test_both_checkers_pass(action):
    from gymnasium.utils.env_checker import check_env

    check_env(gym.make("EKFSLAM-v0", action=action, observation=DICT, max_episode_steps=30).unwrapped,
              skip_render_check=True)  # fmt: skip
    env_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    env_checker.check_env(EKFSLAMEnv(action=action, observation=DICT, max_episode_steps=30), warn=True)


def test_a_box_observation_refuses_it():
    with pytest.raises(ValueError, match="last_action"):
        EKFSLAMEnv(observation={"kind": "box", "last_action": True})
    with pytest.raises(ValueError, match="last_action"):
        EKFSLAMEnv(observation={"kind": "dict", "last_action": 1})
