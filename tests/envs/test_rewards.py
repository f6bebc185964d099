"""Env rewards: the sum of the terms, information gain, discovery, coverage, the term list, walls."""

import math
import pickle

import numpy as np
import pytest

from ekfslam_gym.envs import EKFSLAMEnv


def test_reward_is_the_sum_of_its_terms_and_information_gain_telescopes():
    weights = {"collision": 0.5, "step_cost": 0.1, "pose_variance": 0.3}
    env = EKFSLAMEnv(reward=weights)
    _, info = env.reset(seed=2)
    log_det_0 = info["log_det"]
    rng = np.random.default_rng(0)
    weights = {**weights, "info_gain": 1.0}
    gains, truncated, terminated = [], False, False
    while not (terminated or truncated):
        _, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, 2))
        terms = info["reward_terms"]
        assert reward == pytest.approx(sum(w * terms[name] for name, w in weights.items()), abs=1e-12)
        gains.append(terms["info_gain"])
    assert sum(gains) == pytest.approx(log_det_0 - info["log_det"], abs=1e-8 * max(1, abs(log_det_0)))
    sign, exact = np.linalg.slogdet(env.filter.cov)
    assert sign > 0 and info["log_det"] == pytest.approx(exact, abs=1e-8 * max(1.0, abs(exact)))


def test_reset_info_carries_the_log_det_of_the_first_corrected_belief():
    env = EKFSLAMEnv()
    _, info = env.reset(seed=11)
    assert info["log_det"] == pytest.approx(np.linalg.slogdet(env.filter.cov)[1], abs=1e-9)
    assert info["landmarks_seen"] == len(info["readings"].ids) > 0


def test_discovery_reward_matches_the_documented_formula():
    env = EKFSLAMEnv()
    env.reset(seed=0)
    ekf = env.filter.copy()
    unseen = int(np.flatnonzero(~ekf.observed)[0])
    r = 3.0
    before = ekf.log_det
    ekf.correct([unseen], [[r, 0.0]])
    sensor = env.config.sensor
    expected = math.log(
        env.config.filter.landmark_prior**2 / (r**2 * sensor.range_std**2 * sensor.bearing_std**2)
    )
    assert before - ekf.log_det == pytest.approx(expected, rel=1e-9)


def test_coverage_shaping_pays_for_newly_looked_at_area_only():
    env = EKFSLAMEnv(reward={"coverage": 2.0})
    env.reset(seed=1)
    area = env.coverage_memory.sum() * 0.25
    total = 0.0
    for _ in range(50):
        *_, info = env.step(np.array([1.0, 0.3]))
        total += info["reward_terms"]["coverage"]
    assert total == pytest.approx(env.coverage_memory.sum() * 0.25 - area)  # m^2, unweighted
    for _ in range(30):  # spinning on the spot looks at nothing new after the first turn
        *_, reward, _, _, info = env.step(np.array([0.0, 1.0]))
    assert info["reward_terms"]["coverage"] == 0.0
    assert EKFSLAMEnv().reset(seed=1)[1]["reward_terms"]["coverage"] == 0.0  # every term, at reset too


def test_one_list_of_reward_terms_makes_the_config_fields_and_the_info():
    import dataclasses

    from ekfslam_gym.envs import RewardConfig
    from ekfslam_gym.envs.rewards import REWARD_NAMES, REWARD_TERMS

    assert tuple(f.name for f in dataclasses.fields(RewardConfig)) == REWARD_NAMES
    assert all(getattr(RewardConfig(), t.name) == t.default for t in REWARD_TERMS)
    # Every term, unweighted, in the list's order, whatever its weight; the reward weighs them.
    env = EKFSLAMEnv(reward={"info_gain": 0.0, "step_cost": 0.25, "pose_variance": 0.5})
    env.reset(seed=0)
    _, reward, *_, info = env.step(np.array([0.3, 0.1]))
    terms = info["reward_terms"]
    assert list(terms) == list(REWARD_NAMES)
    assert terms["step_cost"] == -1.0 and terms["info_gain"] != 0.0
    assert reward == terms["collision"] + 0.25 * terms["step_cost"] + 0.5 * terms["pose_variance"]
    assert pickle.loads(pickle.dumps(RewardConfig(collision=3.0))) == RewardConfig(collision=3.0)


def test_driving_into_a_wall_is_reported_penalised_and_optionally_terminates():
    env = EKFSLAMEnv(reward={"collision": 2.0})
    env.reset(seed=0)
    hits = []
    for _ in range(400):
        _, _, terminated, truncated, info = env.step(np.array([1.0, 0.0]))
        if info["collision"]:
            hits.append(info["reward_terms"]["collision"])
        assert not terminated
    assert hits and all(h == -1.0 for h in hits)  # unweighted
    strict = EKFSLAMEnv(terminate_on_collision=True)
    strict.reset(seed=0)
    for _ in range(400):
        _, _, terminated, _, info = strict.step(np.array([1.0, 0.0]))
        if terminated:
            break
    assert terminated and info["collision"]
