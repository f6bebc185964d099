"""Env configuration: bad configs named, YAML presets, merging, filter variants and motion models."""

import math

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401  (registers the envs)
from ekfslam_gym.envs import PRESETS, EKFSLAMEnv, EnvConfig
from ekfslam_gym.envs.config import FilterConfig


@pytest.mark.parametrize(
    "overrides, field",
    [
        (dict(sensor={"max_range": -1.0}), "max_range"),
        (dict(world={"n_landmarks": 0}), "world.n_landmarks"),
        (dict(world={"layout": "castle"}), "world.layout"),
        (dict(reward={"info_gan": 1.0}), "reward.info_gan"),
        (dict(filter={"landmark_prior": "big"}), "filter.landmark_prior"),
        (dict(max_episode_steps=0), "max_episode_steps"),
        (dict(observation={"kind": "image"}), "observation.kind"),
        (dict(filter={"motion_model": "tracks"}), "filter.motion_model"),
        (dict(filter={"variant": "ukf"}), "filter.variant"),
        (dict(filter={"iterations": 0}), "filter.iterations"),
        (dict(filter={"iterations": 2.5}), "filter.iterations"),
    ],
)
def test_bad_configs_raise_errors_naming_the_field(overrides, field):
    error = ValueError
    if "max_episode_steps" in overrides:
        # gymnasium's TimeLimit refuses it before the env is built: ValueError in 1.4, AssertionError in 1.2
        # (the version RLlib pins)
        error = (ValueError, AssertionError)
    with pytest.raises(error, match=field.replace(".", r"\.")):
        gym.make("EKFSLAM-v0", **overrides)


def test_yaml_configs_match_the_registered_presets():
    from pathlib import Path

    root = Path(__file__).resolve().parents[2] / "configs" / "env"
    assert EnvConfig.from_yaml(root / "default.yaml") == EnvConfig()
    for env_id, name in (("EKFSLAM-Loop-v0", "loop"), ("EKFSLAM-Large-v0", "large")):
        from_yaml = EnvConfig.from_yaml(root / f"{name}.yaml")
        assert from_yaml == EnvConfig.from_overrides(**PRESETS[env_id])
        assert gym.make(env_id).unwrapped.config == from_yaml
    assert EKFSLAMEnv(config=root / "loop.yaml").config.world.layout == "loop"


def test_config_merges_onto_the_ids_preset_and_replacing_it_is_asked_for(tmp_path):
    """``config=`` (a mapping or a YAML file) changes the id's preset where it says, and nothing else; only
    ``preset=None`` starts from the defaults (and then the defaults' step limit is the TimeLimit's)."""
    large = EnvConfig.from_overrides(**PRESETS["EKFSLAM-Large-v0"])
    expected = EnvConfig.from_overrides(large, world={"n_landmarks": 40})
    yaml_file = tmp_path / "forty.yaml"
    yaml_file.write_text("world:\n  n_landmarks: 40\n")
    for config in ({"world": {"n_landmarks": 40}}, yaml_file, str(yaml_file)):
        env = gym.make("EKFSLAM-Large-v0", config=config)
        assert env.unwrapped.config == expected
        assert env.spec.max_episode_steps == 1000
    assert expected.world.layout == "rooms" and expected.world.layout_kwargs["width"] == 40.0
    loop = gym.make("EKFSLAM-Loop-v0", config={"max_episode_steps": 900}, sensor={"max_range": 4.0})
    assert loop.unwrapped.config == EnvConfig.from_overrides(
        EnvConfig.from_overrides(**PRESETS["EKFSLAM-Loop-v0"]),
        max_episode_steps=900,
        sensor={"max_range": 4.0},
    )
    assert loop.spec.max_episode_steps == 900

    replaced = gym.make("EKFSLAM-Large-v0", config={"world": {"n_landmarks": 40}}, preset=None)
    assert replaced.unwrapped.config == EnvConfig.from_overrides(world={"n_landmarks": 40})
    assert replaced.spec.max_episode_steps == 500
    complete = EnvConfig.from_overrides(world={"n_landmarks": 12})  # a whole EnvConfig is used as it is
    assert gym.make("EKFSLAM-Large-v0", config=complete).unwrapped.config == complete
    assert EKFSLAMEnv(preset="EKFSLAM-Large-v0").config == large
    assert EKFSLAMEnv().config == EnvConfig()
    with pytest.raises(ValueError, match=r"unknown preset 'EKFSLAM-Huge-v0'; known: \[.*'EKFSLAM-Large-v0'"):
        EKFSLAMEnv(preset="EKFSLAM-Huge-v0")


def test_large_variant_has_at_least_100_landmarks_and_truncates_at_its_own_limit():
    env = gym.make("EKFSLAM-Large-v0")
    env.reset(seed=0)
    assert env.unwrapped.filter.n_landmarks >= 100
    short = gym.make("EKFSLAM-v0", max_episode_steps=7)
    short.reset(seed=0)
    flags = [short.step(np.zeros(2))[3] for _ in range(7)]
    assert flags == [False] * 6 + [True]


FILTER_SETTINGS = [
    {"variant": "ekf"},
    {"variant": "fej"},
    {"variant": "iekf", "iterations": 3},
    {"motion_model": "wheels"},
    {"motion_model": "wheels", "variant": "fej"},
    {"motion_model": "velocity", "variant": "iekf"},
]


@pytest.mark.parametrize("settings", FILTER_SETTINGS, ids=lambda s: "-".join(map(str, s.values())))
def test_every_filter_variant_and_motion_model_runs_and_passes_the_checker(settings):
    """The env builds its filter from ``filter.variant``/``iterations``/``motion_model``, reads the matching
    odometry, and its info["log_det"] is the exact log det of the filter's covariance throughout."""
    from gymnasium.utils.env_checker import check_env

    env = gym.make("EKFSLAM-v0", filter=settings, max_episode_steps=60)
    check_env(env.unwrapped, skip_render_check=True)
    _, info = env.reset(seed=3)
    ekf = env.unwrapped.filter  # a new filter at every reset
    assert ekf.variant == settings.get("variant", "ekf")
    assert ekf.motion_model == settings.get("motion_model", FilterConfig().motion_model)
    assert ekf.iterations == settings.get("iterations", 5)
    width = 2 if ekf.motion_model == "velocity" else 3
    rng = np.random.default_rng(3)
    for t in range(60):
        assert info["log_det"] == pytest.approx(np.linalg.slogdet(ekf.cov)[1], abs=1e-8), t
        _, _, terminated, truncated, info = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        assert info["odometry"].shape == (width,) and info["odometry_cov"].shape == (width, width)
        assert not info["filter_failed"] and np.isfinite(info["pose_nees"])
        if terminated or truncated:
            break
    assert t == 59
    env.close()


def test_wheels_filter_takes_the_worlds_wheel_base_and_reads_wheel_odometry():
    env = EKFSLAMEnv(filter={"motion_model": "wheels"})
    env.reset(seed=5)
    assert env.filter.wheel_base == env.world.wheel_noise.wheel_base
    for _ in range(3):
        *_, info = env.step(np.array([0.8, 0.5], dtype=np.float32))
    left, right, slip = info["odometry"]
    before, after = env.world.last_motion
    # the wheels' travels (m) within a few of their standard deviations (1e-3 m here) of the true turn and
    # the commanded travel; in free space no slip beyond its floor
    assert (right - left) / env.filter.wheel_base == pytest.approx(after[2] - before[2], abs=0.02)
    assert 0.5 * (left + right) == pytest.approx(0.8 * 0.1, abs=0.005)
    assert abs(slip) < 1e-4


@pytest.mark.parametrize("motion_model", ["odometry", "velocity", "wheels"])
def test_greedy_planner_drives_with_every_motion_model(motion_model):
    """The greedy planner rolls the env's filter forward with the primitives' controls in the filter's own
    motion model: every model's controls move the filter along the same arc."""
    from ekfslam_gym.agents import GreedyInfoGainAgent
    from ekfslam_gym.agents.greedy import primitive_controls

    env = gym.make("EKFSLAM-v0", filter={"motion_model": motion_model}, max_episode_steps=15)
    observation, _ = env.reset(seed=2)
    agent = GreedyInfoGainAgent()
    agent.reset(env, seed=2)
    for _ in range(15):
        action = agent.act(observation)
        assert action.shape == (2,) and np.all(np.abs(action) <= 1)
        observation, _, terminated, truncated, info = env.step(action)
        assert not info["filter_failed"]
        if terminated or truncated:
            break
    unwrapped = env.unwrapped
    noise = {
        "odometry": unwrapped.config.odometry,
        "velocity": unwrapped.world.velocity_noise,
        "wheels": unwrapped.world.wheel_noise,
    }[motion_model]
    controls, covs, poses = primitive_controls(0.8, 1.2, 0.1, 4, motion_model, noise)
    ekf = unwrapped.filter.copy()
    start = ekf.pose.copy()
    for control, cov in zip(controls, covs):
        ekf.predict(control, control_cov=cov)
    c, s = math.cos(start[2]), math.sin(start[2])
    expected = start + [
        c * poses[-1, 0] - s * poses[-1, 1],
        s * poses[-1, 0] + c * poses[-1, 1],
        poses[-1, 2],
    ]
    expected[2] = (expected[2] + math.pi) % (2 * math.pi) - math.pi
    np.testing.assert_allclose(ekf.pose, expected, atol=1e-12)
    env.close()
