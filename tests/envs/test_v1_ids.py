"""The v1 ids: one per layout family with its tiers, the Large, and the mixed-families id for generalists."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401  (registers the ids)
from ekfslam_gym.envs import EKFSLAMEnv
from ekfslam_gym.envs.presets import (
    DEFAULT_TIER,
    DESCRIPTIONS,
    FAMILY_IDS,
    MIX_ID,
    PRESETS,
    TIER_EPISODE_TIME,
    family_id,
)
from ekfslam_gym.seeds import HELDOUT_FAMILIES, TRAINING_FAMILIES
from ekfslam_gym.sim.families import FAMILIES, TIERS, world_section


def test_every_family_has_a_registered_v1_id_and_the_v0_worlds_are_their_medium_tiers():
    assert sorted(FAMILY_IDS.values()) == sorted(FAMILIES)
    assert family_id("arena") == "EKFSLAM-v1" and family_id("loop") == "EKFSLAM-Loop-v1"
    assert family_id("figure_eight") == "EKFSLAM-FigureEight-v1"
    for env_id in [*FAMILY_IDS, "EKFSLAM-Large-v1", MIX_ID]:
        assert env_id in gym.registry and env_id in PRESETS and DESCRIPTIONS[env_id]
    for v0, v1 in (
        ("EKFSLAM-v0", "EKFSLAM-v1"),
        ("EKFSLAM-Loop-v0", "EKFSLAM-Loop-v1"),
        ("EKFSLAM-Large-v0", "EKFSLAM-Large-v1"),
    ):
        old, new = gym.make(v0).unwrapped, gym.make(v1).unwrapped
        old.reset(seed=5)
        new.reset(seed=5)  # the initial draw leaves the world's stream where it was: the same world
        np.testing.assert_array_equal(old.true_landmarks, new.true_landmarks)
        np.testing.assert_array_equal(old.world.layout.walls, new.world.layout.walls)


@pytest.mark.parametrize("tier", TIERS)
@pytest.mark.parametrize("env_id", sorted(FAMILY_IDS))
def test_a_family_id_at_a_tier_is_the_familys_world_for_the_tiers_time(env_id, tier):
    env = gym.make(env_id, tier=tier, action={"kind": "primitives"})
    config = env.unwrapped.config
    expected = world_section(FAMILY_IDS[env_id], tier)
    assert config.world.layout == expected["layout"] and config.world.n_landmarks == expected["n_landmarks"]
    assert dict(config.world.layout_kwargs) == expected["layout_kwargs"]
    assert config.episode_time == TIER_EPISODE_TIME[tier]
    assert env.unwrapped._max_steps * config.action.hold == round(TIER_EPISODE_TIME[tier] / config.dt)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    assert env.unwrapped.filter.n_landmarks == expected["n_landmarks"]


def test_the_default_tier_and_the_tiers_errors():
    assert (
        gym.make("EKFSLAM-Maze-v1").unwrapped.config
        == gym.make("EKFSLAM-Maze-v1", tier=DEFAULT_TIER).unwrapped.config
    )
    with pytest.raises(ValueError, match="tier must be one of easy|medium|hard"):
        gym.make("EKFSLAM-Maze-v1", tier="brutal")
    with pytest.raises(ValueError, match="tier= applies to the family ids"):
        gym.make("EKFSLAM-Large-v1", tier="easy")
    # A config merges onto the tier's preset, and a user's world section wins over it.
    env = EKFSLAMEnv(preset="EKFSLAM-Office-v1", tier="hard", config={"world": {"n_landmarks": 12}})
    assert env.config.world.layout == "office" and env.config.world.n_landmarks == 12
    assert env.config.world.layout_kwargs == world_section("office", "hard")["layout_kwargs"]


def test_the_mixed_id_draws_training_families_and_tiers_from_the_seed_with_fixed_spaces():
    env = gym.make(MIX_ID)
    space = env.observation_space
    drawn = set()
    for seed in range(40):
        obs, _ = env.reset(seed=seed)
        base = env.unwrapped
        drawn.add((base.family, base.tier))
        assert env.observation_space == space and space.contains(obs)
        assert base.config.world.layout == world_section("arena", DEFAULT_TIER)["layout"]  # config untouched
        assert base.world.layout.name == base.family
        assert base.filter.n_landmarks == world_section(base.family, base.tier)["n_landmarks"]
        assert base._max_steps == round(TIER_EPISODE_TIME[base.tier] / base.config.dt)
        obs, *_ = env.step(env.action_space.sample())
        assert space.contains(obs)
    assert {f for f, _ in drawn} == set(TRAINING_FAMILIES) and {t for _, t in drawn} == set(TIERS)
    again = gym.make(MIX_ID)
    for seed in (3, 17):
        first, _ = again.reset(seed=seed)
        second, _ = env.reset(seed=seed)
        assert (again.unwrapped.family, again.unwrapped.tier) == (env.unwrapped.family, env.unwrapped.tier)
        np.testing.assert_array_equal(first, second)


def test_the_mixed_id_keeps_a_given_step_limit_and_refuses_held_out_families():
    env = gym.make(MIX_ID, max_episode_steps=25, tiers=("hard",))
    for seed in range(3):
        env.reset(seed=seed)
        assert env.unwrapped._max_steps == 25 and env.unwrapped.tier == "hard"
    only = gym.make(MIX_ID, families=["loop"], tiers=["easy"])
    only.reset(seed=0)
    assert (only.unwrapped.family, only.unwrapped.tier) == ("loop", "easy")
    with pytest.raises(ValueError, match=f"held-out layout family '{HELDOUT_FAMILIES[0]}'"):
        gym.make(MIX_ID, families=[HELDOUT_FAMILIES[0]])
    with pytest.raises(ValueError, match="tiers must be"):
        gym.make(MIX_ID, tiers=["brutal"])
