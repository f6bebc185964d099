"""The v1 ids' episode: no incentive to delay the map's completion, one step-limit rule in simulated time, the
filter's initial draw on, and a Large that the frontier planner can complete."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.wrappers import TimeLimit

import ekfslam_gym  # noqa: F401  (registers the ids)
from ekfslam_gym.envs import EKFSLAMEnv
from ekfslam_gym.envs.presets import PRESETS

V1_IDS = sorted(i for i in PRESETS if i.endswith("-v1"))
# A small world whose map the frontier planner completes in seconds: 12 landmarks, done_std 0.2 m.
SMALL = {
    "world": {"n_landmarks": 12, "layout_kwargs": {"width": 14.0, "height": 14.0}},
    "done_std": 0.2,
    "episode_time": 50.0,
}


def _time_limits(env: gym.Env) -> list[int]:
    limits = []
    while isinstance(env, gym.Wrapper):
        if isinstance(env, TimeLimit):
            limits.append(env._max_episode_steps)
        env = env.env
    return limits


def _episode(env: gym.Env, act, seed: int = 0) -> dict:
    """Run ``act(step, observation)`` to the episode's end: the actions, rewards, flags and the last info."""
    obs, info = env.reset(seed=seed)
    out = {"log_det_0": info["log_det"], "actions": [], "rewards": [], "terminated": [], "truncated": []}
    while True:
        action = act(len(out["actions"]), obs)
        obs, reward, terminated, truncated, info = env.step(action)
        for key, value in zip(
            ("actions", "rewards", "terminated", "truncated"), (action, reward, terminated, truncated)
        ):
            out[key].append(value)
        if terminated or truncated:
            break
    out["info"] = info
    return out


def _frontier_after(env: gym.Env, wait: int, seed: int = 0):
    """The frontier planner, after standing still for ``wait`` env steps."""
    from ekfslam_gym.agents import make_agent

    agent = make_agent("frontier")
    first = True

    def act(step: int, obs: np.ndarray) -> np.ndarray:
        nonlocal first
        if first:
            agent.reset(env, seed=seed)
            first = False
        return np.zeros(2, dtype=np.float32) if step < wait else agent.act(obs)

    return act


def _time_left(env: gym.Env, obs: np.ndarray) -> float:
    return float(env.unwrapped.observation_layout.part(obs, "globals")[2])


# ------------------------------------------------------------------ no incentive to delay
def test_completing_the_map_sooner_never_earns_less_for_the_same_final_map():
    """A v1 episode runs to its horizon whether or not the map is complete, and its return is log det Sigma_0 -
    log det Sigma_T less the collision terms: a function of the final belief alone, whenever the map was
    completed. Two drives, the frontier planner at once and after standing still for 10 s: both complete the
    map, at different times, and both last the horizon; each one's return is its own log det drop (checked
    against numpy's slogdet), so the two returns differ by their final maps alone; and the same drive with
    the completion criterion off (done_std 0) earns exactly the same rewards, step by step."""
    returns = {}
    for name, wait in (("early", 0), ("late", 100)):
        env = gym.make("EKFSLAM-v1", **SMALL)
        run = _episode(env, _frontier_after(env, wait))
        info = run["info"]
        assert not any(run["terminated"]) and run["truncated"][-1] and len(run["rewards"]) == 500
        assert np.isfinite(info["time_to_complete"])  # the map was complete, and the episode went on
        sign, log_det_t = np.linalg.slogdet(env.unwrapped.filter.cov)
        collisions = info["collisions"] * env.unwrapped.config.reward.collision
        assert sign > 0
        np.testing.assert_allclose(sum(run["rewards"]), run["log_det_0"] - log_det_t - collisions, atol=1e-6)
        returns[name] = (info["time_to_complete"], sum(run["rewards"]), log_det_t, collisions)
        never = gym.make("EKFSLAM-v1", **{**SMALL, "done_std": 0.0})
        replay = _episode(never, lambda step, obs, actions=run["actions"]: actions[step])
        np.testing.assert_array_equal(replay["rewards"], run["rewards"])
        assert replay["info"]["time_to_complete"] == np.inf
    (t_early, r_early, ld_early, c_early), (t_late, r_late, ld_late, c_late) = (
        returns["early"],
        returns["late"],
    )
    assert t_early + 5.0 < t_late
    # The returns differ by the final maps' log dets (and collisions) alone, not by when each was complete.
    np.testing.assert_allclose(r_early - r_late, (ld_late - ld_early) - (c_early - c_late), atol=1e-6)


def test_v0_still_ends_on_a_complete_map_and_reports_when():
    env = gym.make("EKFSLAM-v0", **SMALL)
    run = _episode(env, _frontier_after(env, 0))
    assert run["terminated"][-1] and len(run["rewards"]) < 500
    assert run["info"]["time_to_complete"] == pytest.approx(run["info"]["step"] * 0.1)


def test_time_to_complete_is_inf_until_the_map_is_complete_then_the_time_it_first_was():
    env = gym.make("EKFSLAM-v1", **SMALL)
    act = _frontier_after(env, 0)
    obs, info = env.reset(seed=0)
    assert info["time_to_complete"] == np.inf
    times = []
    for step in range(500):
        obs, _, _, _, info = env.step(act(step, obs))
        times.append(info["time_to_complete"])
    first = next(i for i, t in enumerate(times) if np.isfinite(t))
    assert all(t == np.inf for t in times[:first]) and set(times[first:]) == {round((first + 1) * 0.1, 9)}


# ------------------------------------------------------------------ one step-limit rule
@pytest.mark.parametrize(
    "action, env_steps",
    [
        ({"kind": "velocity"}, 1500),
        ({"kind": "velocity", "hold": 4}, 375),
        ({"kind": "primitives"}, 150),
        ({"kind": "primitives", "hold": 7}, 215),  # 7 does not divide 1500: the last step runs 5 past
        ({"kind": "waypoint"}, 150),
    ],
)
def test_every_action_kind_gets_the_same_simulated_time(action, env_steps):
    """EKFSLAM-v1 lasts 150 s of simulated time (1500 control steps) whatever the action kind: the env's limit,
    gym.make's and the env built directly agree, and there is no TimeLimit unless one is asked for."""
    env = gym.make("EKFSLAM-v1", action=action)
    direct = EKFSLAMEnv(preset="EKFSLAM-v1", action=action)
    assert env.unwrapped.config.episode_time == 150.0
    assert env.unwrapped._max_steps == direct._max_steps == env_steps
    assert env.spec.max_episode_steps is None and _time_limits(env) == []
    hold = env.unwrapped.config.action.hold
    assert 0 <= env_steps * hold - 1500 < hold
    if action["kind"] != "waypoint":  # a waypoint's macro step may end early, when its goal is reached
        obs, _ = env.reset(seed=0)
        flags = []
        for _ in range(env_steps + 3):
            obs, _, terminated, truncated, info = env.step(env.action_space.sample())
            flags.append(truncated)
            if terminated or truncated:
                break
        assert flags == [False] * (env_steps - 1) + [True]
        assert info["step"] == env_steps * hold and _time_left(env, obs) == 0.0


@pytest.mark.parametrize("limit", [50, 500, 37])
def test_max_episode_steps_does_what_gymnasium_documents_whatever_its_value(limit):
    """``gym.make(id, max_episode_steps=N)`` wraps the env in a TimeLimit of N env steps, and the episode is N
    env steps long: 500 given with primitives is 500 primitives (in v0 it was 50, because 500 equals the
    registered limit), 50 is 50."""
    env = gym.make("EKFSLAM-v1", action={"kind": "primitives"}, max_episode_steps=limit)
    assert env.spec.max_episode_steps == limit and _time_limits(env) == [limit]
    assert env.unwrapped.config.max_episode_steps == env.unwrapped._max_steps == limit
    obs, _ = env.reset(seed=0)
    assert _time_left(env, obs) == 1.0
    for step in range(1, limit + 1):
        obs, _, terminated, truncated, _ = env.step(0)
        assert truncated == (step == limit) and not terminated
    assert _time_left(env, obs) == 0.0


def test_a_step_limit_in_the_config_or_a_time_is_the_users_and_two_different_ones_are_an_error():
    env = gym.make("EKFSLAM-v1", config={"max_episode_steps": 500}, action={"kind": "primitives"})
    assert env.unwrapped._max_steps == 500 and _time_limits(env) == []
    timed = gym.make("EKFSLAM-v1", episode_time=20.0, action={"kind": "primitives"})
    assert timed.unwrapped._max_steps == 20
    hard = gym.make("EKFSLAM-v1", tier="hard", action={"kind": "primitives"})
    assert hard.unwrapped._max_steps == 330
    same = gym.make("EKFSLAM-v1", max_episode_steps=30, config={"max_episode_steps": 30})
    assert same.unwrapped._max_steps == 30
    with pytest.raises(ValueError, match="two step limits"):
        gym.make("EKFSLAM-v1", max_episode_steps=30, config={"max_episode_steps": 40})
    with pytest.raises(ValueError, match="episode_time must be a whole number of dt"):
        gym.make("EKFSLAM-v1", episode_time=1.234)
    with pytest.raises(ValueError, match="max_episode_steps may be None only with an episode_time"):
        EKFSLAMEnv(max_episode_steps=None)


def test_the_limit_survives_pickling_rebuilding_from_the_spec_and_vector_envs():
    env = gym.make("EKFSLAM-Loop-v1", max_episode_steps=12)
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros(2, dtype=np.float32))
    clone = pickle.loads(pickle.dumps(env))
    assert [clone.step(np.zeros(2, dtype=np.float32))[3] for _ in range(7)] == [False] * 6 + [True]
    rebuilt = gym.make(env.spec)
    assert rebuilt.unwrapped._max_steps == 12 and _time_limits(rebuilt) == [12]
    vector = gym.make_vec("EKFSLAM-v1", num_envs=2, vectorization_mode="sync", episode_time=1.0)
    vector.reset(seed=0)
    truncated = [vector.step(np.zeros((2, 2), dtype=np.float32))[3] for _ in range(10)]
    assert truncated[-1].all() and not any(t.any() for t in truncated[:-1])
    vector.close()


# ------------------------------------------------------------------ the filter's initial draw
@pytest.mark.parametrize("env_id", V1_IDS)
def test_v1_draws_the_filters_initial_pose_from_its_prior(env_id):
    env = gym.make(env_id)
    assert env.unwrapped.config.filter.initial_draw
    _, info = env.reset(seed=0)
    assert not np.array_equal(info["pose"], info["true_pose"])
    v0 = gym.make(env_id.replace("-v1", "-v0")) if env_id.replace("-v1", "-v0") in PRESETS else None
    if v0 is not None:
        assert not v0.unwrapped.config.filter.initial_draw
        _, info = v0.reset(seed=0)
        np.testing.assert_array_equal(info["pose"], info["true_pose"])


# ------------------------------------------------------------------ a Large that can be completed
@pytest.mark.slow
def test_the_frontier_planner_sees_nine_tenths_of_large_v1_within_its_horizon():
    """The frontier planner's median seen fraction over five evaluation seeds at the end of EKFSLAM-Large-v1's
    600 s is at least 0.9 (in 100 s, v0's horizon, it saw less than half)."""
    from ekfslam_gym.agents import make_agent

    from ekfslam_gym.evaluation.rollout import evaluate_agent
    from ekfslam_gym.seeds import EVAL_SEEDS

    episodes = evaluate_agent(make_agent("frontier"), "EKFSLAM-Large-v1", EVAL_SEEDS[:5])
    assert all(e["steps"] == 6000 for e in episodes)
    assert np.median([e["seen_fraction"] for e in episodes]) >= 0.9
