"""The team env (``ekfslam_gym.multi``): PettingZoo's API tests, the information-gain identity, one robot against
the single-robot env, seeded determinism and the config's errors."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pettingzoo")

from pettingzoo.test import api_test, parallel_api_test  # noqa: E402

from ekfslam_gym.envs import EKFSLAMEnv  # noqa: E402
from ekfslam_gym.envs.rewards import REWARD_NAMES  # noqa: E402
from ekfslam_gym.multi import env, parallel_env  # noqa: E402
from ekfslam_gym.multi.observation import TEAMMATE_FEATURES  # noqa: E402

SMALL = {"world": {"n_landmarks": 20}, "max_episode_steps": 12}


def random_actions(team, rng):
    return {agent: int(rng.integers(team.action_space(agent).n)) for agent in team.agents}


def test_parallel_api():
    parallel_api_test(parallel_env(n_robots=3, **SMALL), num_cycles=30)


def test_aec_api():
    api_test(env(n_robots=3, **SMALL), num_cycles=30)


def test_spaces_and_agents():
    team = parallel_env(n_robots=4)
    assert team.possible_agents == ["robot_0", "robot_1", "robot_2", "robot_3"]
    single = EKFSLAMEnv(preset=None, action={"kind": "primitives"})
    size = single.observation_space.shape[0] + TEAMMATE_FEATURES * team.config.team.teammate_slots
    for agent in team.possible_agents:
        assert team.observation_space(agent).shape == (size,)
        assert team.action_space(agent) == single.action_space
    observations, infos = team.reset(seed=1)
    assert set(observations) == set(infos) == set(team.possible_agents)
    # Four robots: three teammate slots filled, the fourth empty.
    teammates = observations["robot_0"][single.observation_space.shape[0] :].reshape(-1, TEAMMATE_FEATURES)
    assert teammates[:3, 0].tolist() == [1.0, 1.0, 1.0] and not teammates[3].any()


@pytest.mark.parametrize("n_robots", [2, 3])
def test_info_gain_is_the_joint_log_det_drop(n_robots):
    team = parallel_env(n_robots=n_robots, **SMALL)
    _, infos = team.reset(seed=5)
    log_det = infos["robot_0"]["log_det"]
    assert log_det == pytest.approx(np.linalg.slogdet(team.filter.cov)[1], abs=1e-6)
    rng = np.random.default_rng(0)
    while team.agents:
        _, rewards, _, _, infos = team.step(random_actions(team, rng))
        after = infos["robot_0"]["log_det"]
        for info in infos.values():
            assert info["log_det"] == after
            assert list(info["reward_terms"]) == list(REWARD_NAMES)
            assert info["reward_terms"]["info_gain"] == pytest.approx(log_det - after, abs=1e-9)
            assert info["reward_terms"]["collision"] == pytest.approx(
                sum(i["robot_terms"]["collision"] for i in infos.values())
            )
        assert len(set(rewards.values())) == 1  # one team reward
        assert after == pytest.approx(np.linalg.slogdet(team.filter.cov)[1], abs=1e-6)
        log_det = after


def test_one_robot_is_the_single_robot_env():
    """Same seed, same actions: the same belief (mean, covariance, log det), reward and observation, bit for
    bit (the team env draws and filters in the single-robot env's order; the teammate slots are empty)."""
    team = parallel_env(n_robots=1, max_episode_steps=20)
    single = EKFSLAMEnv(preset=None, action={"kind": "primitives"}, max_episode_steps=20)
    team_obs, team_info = team.reset(seed=3)
    single_obs, single_info = single.reset(seed=3)
    size = single_obs.shape[0]
    np.testing.assert_array_equal(team_obs["robot_0"][:size], single_obs)
    assert not team_obs["robot_0"][size:].any()
    rng = np.random.default_rng(7)
    for _ in range(20):
        action = int(rng.integers(9))
        team_obs, rewards, terminated, truncated, infos = team.step({"robot_0": action})
        single_obs, reward, single_terminated, single_truncated, info = single.step(np.int64(action))
        np.testing.assert_array_equal(team.filter.mean, single.filter.mean)
        np.testing.assert_array_equal(team.filter.cov, single.filter.cov)
        assert infos["robot_0"]["log_det"] == info["log_det"]
        assert infos["robot_0"]["reward_terms"] == info["reward_terms"]
        assert rewards["robot_0"] == reward
        np.testing.assert_array_equal(infos["robot_0"]["true_pose"], info["true_pose"])
        np.testing.assert_array_equal(team_obs["robot_0"][:size], single_obs)
        assert (terminated["robot_0"], truncated["robot_0"]) == (single_terminated, single_truncated)
        if single_terminated or single_truncated:
            break


def test_seeded_determinism():
    def rollout():
        team = parallel_env(n_robots=3, **SMALL)
        observations, _ = team.reset(seed=11)
        rng = np.random.default_rng(2)
        record = [np.concatenate(list(observations.values()))]
        while team.agents:
            observations, rewards, _, _, infos = team.step(random_actions(team, rng))
            record.append(np.concatenate(list(observations.values())))
            record.append(np.array([rewards["robot_0"], infos["robot_2"]["log_det"]]))
        return record

    first, second = rollout(), rollout()
    assert len(first) == len(second)
    for a, b in zip(first, second):
        np.testing.assert_array_equal(a, b)


def test_reset_seed_reproduces_and_reseeds():
    team = parallel_env(n_robots=2, **SMALL)
    a, _ = team.reset(seed=4)
    b, _ = team.reset(seed=5)
    c, _ = team.reset(seed=4)
    np.testing.assert_array_equal(a["robot_1"], c["robot_1"])
    assert not np.array_equal(a["robot_1"], b["robot_1"])


def test_robots_read_each_other_and_the_filter_fuses_it():
    """Two robots start 1 m apart facing the same way: neither is in the other's half-circle view, so turning
    one in place brings the other into view; their relative position then becomes more certain than the dead
    reckoning alone leaves it."""

    def relative_variance(readings: bool) -> float:
        team = parallel_env(n_robots=2, team={"robot_readings": readings}, max_episode_steps=6)
        team.reset(seed=2)
        turn_left = 7  # (0, 1): turning in place
        for _ in range(6):
            team.step({"robot_0": turn_left, "robot_1": 0})
        cov = team.filter.cov
        block = cov[3:5, 3:5] + cov[0:2, 0:2] - cov[3:5, 0:2] - cov[0:2, 3:5]
        return float(np.trace(block))

    assert relative_variance(True) < relative_variance(False)


def test_errors_name_the_field():
    with pytest.raises(ValueError, match="team.n_robots"):
        parallel_env(n_robots=6)
    with pytest.raises(ValueError, match="action.kind"):
        parallel_env(action={"kind": "velocity"})
    with pytest.raises(ValueError, match="filter.association"):
        parallel_env(filter={"association": "jcbc"})
    with pytest.raises(ValueError, match="unknown config field team.robots"):
        parallel_env(team={"robots": 2})
    team = parallel_env(n_robots=2, **SMALL)
    team.reset(seed=0)
    with pytest.raises(ValueError, match="missing"):
        team.step({"robot_0": 0})


def test_registered_with_pettingzoo():
    import pettingzoo

    from ekfslam_gym.multi import ENV_ID

    team = pettingzoo.make("parallel", ENV_ID, n_robots=2, max_episode_steps=3)
    assert team.possible_agents == ["robot_0", "robot_1"]
    observations, _ = team.reset(seed=0)
    reference, _ = parallel_env(n_robots=2, max_episode_steps=3).reset(seed=0)
    np.testing.assert_array_equal(observations["robot_1"], reference["robot_1"])
    aec = pettingzoo.make("aec", ENV_ID, n_robots=2)
    aec.reset(seed=0)
    assert aec.agent_selection == "robot_0"


@pytest.mark.parametrize(
    "filter_settings",
    [{"variant": "fej"}, {"variant": "iekf"}, {"motion_model": "odometry"}, {"motion_model": "velocity"},
     {"update": "sequential"}, {"init_mode": "course"}],
    ids=lambda s: "-".join(map(str, s.values())),
)  # fmt: skip
def test_filter_settings_apply_to_the_team(filter_settings):
    """The filter section's variants and models reach the team filter, and the identity holds under each."""
    team = parallel_env(n_robots=2, filter=filter_settings, **SMALL)
    _, infos = team.reset(seed=8)
    for name, value in filter_settings.items():
        assert getattr(team.filter.settings, name) == value
    rng = np.random.default_rng(1)
    log_det = infos["robot_0"]["log_det"]
    for _ in range(4):
        _, _, _, _, infos = team.step(random_actions(team, rng))
        assert infos["robot_1"]["reward_terms"]["info_gain"] == pytest.approx(
            log_det - infos["robot_1"]["log_det"]
        )
        log_det = infos["robot_1"]["log_det"]
    assert log_det == pytest.approx(np.linalg.slogdet(team.filter.cov)[1], abs=1e-6)
