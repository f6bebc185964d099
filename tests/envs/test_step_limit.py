"""The step limit: registered and given limits, pickling and rebuilding, macro actions' episode time."""

import pickle

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401  (registers the envs)
from ekfslam_gym.envs import PRESETS, EKFSLAMEnv, EnvConfig
from tests.envs.helpers import ENV_IDS


def time_left(env, obs) -> float:
    return float(env.unwrapped.observation_layout.part(obs, "globals")[2])


def time_limits(env) -> list[int]:
    """The limits of the TimeLimit wrappers around the env, outermost first."""
    limits = []
    while isinstance(env, gym.Wrapper):
        if isinstance(env, gym.wrappers.TimeLimit):
            limits.append(env.spec.max_episode_steps)
        env = env.env
    return limits


def run_to_truncation(env, steps):
    """Zero actions (no landmark becomes certain, nothing terminates): the time left and truncation flags."""
    obs, _ = env.reset(seed=0)
    left, flags = [time_left(env, obs)], []
    for _ in range(steps):
        obs, _, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
        assert not terminated
        left.append(time_left(env, obs))
        flags.append(truncated)
        if truncated:
            break
    return np.array(left), flags


# v1: tests/envs/test_v1_episode.py
@pytest.mark.parametrize("env_id", [i for i in ENV_IDS if i.endswith("-v0")])
def test_registered_ids_carry_their_preset_step_limit(env_id):
    limit = EnvConfig.from_overrides(**PRESETS[env_id]).max_episode_steps
    assert gym.spec(env_id).max_episode_steps == limit == {"EKFSLAM-v0": 500, "EKFSLAM-Loop-v0": 800,
                                                           "EKFSLAM-Large-v0": 1000}[env_id]  # fmt: skip
    env = gym.make(env_id)
    assert env.spec.max_episode_steps == env.unwrapped.config.max_episode_steps == limit
    assert time_limits(env) == [limit]


@pytest.mark.parametrize("form", ["make", "config"])
@pytest.mark.parametrize("limit", [37, 530])
def test_a_given_step_limit_truncates_and_zeroes_the_time_left_at_that_step(form, limit):
    kwargs = {"max_episode_steps": limit} if form == "make" else {"config": {"max_episode_steps": limit}}
    env = gym.make("EKFSLAM-v0", **kwargs)
    assert env.spec.max_episode_steps == env.unwrapped.config.max_episode_steps == limit
    assert time_limits(env) == [limit]  # one TimeLimit, not the registered one below a new one
    left, flags = run_to_truncation(env, limit + 5)
    assert flags == [False] * (limit - 1) + [True]
    assert left[-1] == 0.0 and left[-2] > 0.0 and left[0] == 1.0
    np.testing.assert_allclose(np.diff(left), -1.0 / limit, atol=1e-6)


def test_the_step_limit_survives_pickling_and_rebuilding_from_the_spec():
    for kwargs in ({"max_episode_steps": 12}, {"config": {"max_episode_steps": 12}}):
        env = gym.make("EKFSLAM-Loop-v0", **kwargs)
        env.reset(seed=0)
        for _ in range(5):
            env.step(np.zeros(2, dtype=np.float32))
        clone = pickle.loads(pickle.dumps(env))
        flags = [clone.step(np.zeros(2, dtype=np.float32))[3] for _ in range(7)]
        assert flags == [False] * 6 + [True]
        rebuilt = gym.make(env.spec)
        assert rebuilt.spec.max_episode_steps == rebuilt.unwrapped.config.max_episode_steps == 12
        assert run_to_truncation(rebuilt, 20)[1] == [False] * 11 + [True]


def test_a_rebuilt_step_limit_pickles_when_gymnasiums_time_limit_is_replaced(monkeypatch):
    """rl-zoo3, once imported, swaps gymnasium's TimeLimit for a subclass of its own everywhere gym.make and
    pickle look it up; the env rebuilt for a config step limit must still pickle (it used to fail then)."""
    import gymnasium.envs.registration as registration
    import gymnasium.wrappers
    import gymnasium.wrappers.common as common

    import ekfslam_gym.envs.horizon  # noqa: F401  (imported before the swap, as when an env was made earlier)

    class PatchedTimeLimit(common.TimeLimit):
        pass

    PatchedTimeLimit.__module__, PatchedTimeLimit.__qualname__ = common.__name__, "TimeLimit"
    for module in (gymnasium.wrappers, common, registration):
        monkeypatch.setattr(module, "TimeLimit", PatchedTimeLimit, raising=False)
    env = gym.make("EKFSLAM-v0", config={"max_episode_steps": 12})
    assert time_limits(env) == [12]
    env.reset(seed=0)
    clone = pickle.loads(pickle.dumps(env))
    assert [clone.step(np.zeros(2, dtype=np.float32))[3] for _ in range(12)] == [False] * 11 + [True]


def test_two_different_step_limits_are_an_error_and_no_time_limit_leaves_the_env_its_own():
    with pytest.raises(ValueError, match="two step limits"):
        gym.make("EKFSLAM-v0", max_episode_steps=30, config={"max_episode_steps": 40})
    same = gym.make("EKFSLAM-v0", max_episode_steps=30, config={"max_episode_steps": 30})
    assert same.spec.max_episode_steps == 30
    bare = gym.make("EKFSLAM-v0", max_episode_steps=-1, config={"max_episode_steps": 9})
    assert bare.spec.max_episode_steps is None
    left, flags = run_to_truncation(bare, 20)
    assert flags == [False] * 8 + [True] and left[-1] == 0.0
    direct = EKFSLAMEnv(max_episode_steps=9)  # no gym.make: the config alone
    assert run_to_truncation(direct, 20)[1] == [False] * 8 + [True]


@pytest.mark.parametrize(
    "env_id, action, limit",
    [
        ("EKFSLAM-v0", {"kind": "primitives"}, 50),
        ("EKFSLAM-Loop-v0", {"kind": "waypoint"}, 80),
        ("EKFSLAM-v0", {"kind": "velocity", "hold": 4}, 125),
        ("EKFSLAM-v0", {"kind": "primitives", "hold": 1}, 500),
    ],
)
def test_macro_actions_keep_the_registered_episode_time_and_report_their_hold(env_id, action, limit):
    env = gym.make(env_id, action=action)
    cfg = env.unwrapped.config
    assert cfg.action.hold == action.get("hold", 10)  # the effective hold, never None
    assert env.spec.max_episode_steps == cfg.max_episode_steps == limit
    assert time_limits(env) == [limit]
    assert limit * cfg.action.hold == gym.spec(env_id).max_episode_steps  # the same simulated time
    rebuilt = gym.make(env.spec)
    assert rebuilt.spec.max_episode_steps == rebuilt.unwrapped.config.max_episode_steps == limit


def test_a_primitives_episode_truncates_after_the_registered_time():
    env = gym.make("EKFSLAM-v0", action={"kind": "primitives"})
    obs, _ = env.reset(seed=0)
    for step in range(1, 51):
        obs, _, terminated, truncated, info = env.step(7)  # turning in place: nothing ends the episode
        assert not terminated and truncated == (step == 50)
    assert info["step"] == 500 and time_left(env, obs) == 0.0


def test_a_given_step_limit_is_kept_for_macro_actions_and_an_inexact_division_warns():
    for kwargs in (
        {"max_episode_steps": 7},
        {"config": {"max_episode_steps": 7, "action": {"kind": "primitives"}}},
    ):
        env = gym.make("EKFSLAM-v0", **{"action": {"kind": "primitives"}, **kwargs})
        assert env.spec.max_episode_steps == env.unwrapped.config.max_episode_steps == 7
    with pytest.warns(UserWarning, match="does not divide"):
        env = gym.make("EKFSLAM-Large-v0", action={"kind": "primitives", "hold": 3})
    assert env.spec.max_episode_steps == env.unwrapped.config.max_episode_steps == 334


def test_a_change_of_action_kind_takes_the_new_kinds_default_hold():
    assert EnvConfig().action.hold == 1
    assert EnvConfig.from_overrides(action={"kind": "primitives"}).action.hold == 10
    three = EnvConfig.from_overrides(action={"kind": "primitives", "hold": 3})
    assert EnvConfig.from_overrides(three, action={"guard": 0.2}).action.hold == 3  # kind unchanged: kept
    assert EnvConfig.from_overrides(three, action={"kind": "primitives"}).action.hold == 3
    assert EnvConfig.from_overrides(three, action={"kind": "waypoint"}).action.hold == 10
    assert EnvConfig.from_overrides(three, action={"kind": "velocity"}).action.hold == 1
    assert EnvConfig.from_overrides(**three.to_dict()) == three  # a written record reads back
