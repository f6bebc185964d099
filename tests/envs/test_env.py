"""EKFSLAM envs: API conformance across the registry, determinism, rewards, consistency, errors."""

import math
import pickle
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from scipy import stats

import ekfslam_gym  # noqa: F401  (registers the envs)
from ekfslam_gym.envs import PRESETS, EKFSLAMEnv, EnvConfig
from ekfslam_gym.envs.config import FilterConfig

ENV_IDS = sorted(PRESETS)


def rollout(env, seed, steps, action_seed=0):
    """Observations, rewards and true poses of a seeded random-action rollout."""
    obs, info = env.reset(seed=seed)
    rng = np.random.default_rng(action_seed)
    trace = [obs.tobytes(), info["log_det"]]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        trace += [obs.tobytes(), reward, tuple(info["true_pose"]), terminated, truncated]
        if terminated or truncated:
            obs, info = env.reset()
            trace.append(obs.tobytes())
    return trace


# The default observation, and the Dict one with the belief image (a (3, 16, 16) float image).
OBSERVATIONS = {"default": {}, "belief_image": {"observation": {"kind": "dict", "belief_image": True}}}


@pytest.mark.parametrize("observation", OBSERVATIONS)
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_env_checker(env_id, observation):
    from gymnasium.utils.env_checker import check_env

    env = gym.make(env_id, **OBSERVATIONS[observation])
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


@pytest.mark.parametrize("observation", OBSERVATIONS)
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_env_checker(env_id, observation):
    import warnings

    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    with warnings.catch_warnings():
        # The belief image is a float image for a custom extractor (ekfslam_gym.agents.extractors.BeliefCNN), not SB3's
        # uint8 CnnPolicy input: the checker says so in warnings, which are expected.
        warnings.filterwarnings("ignore", message=".*is an image but.*")
        warnings.filterwarnings("ignore", message="The minimal resolution for an image.*")
        sb3_checker.check_env(gym.make(env_id, **OBSERVATIONS[observation]).unwrapped, warn=True)


def test_both_make_spellings_and_dict_observations():
    assert isinstance(gym.make("ekfslam_gym:EKFSLAM-v0").unwrapped, EKFSLAMEnv)
    env = gym.make("EKFSLAM-v0", observation={"kind": "dict"})
    obs, _ = env.reset(seed=1)
    assert isinstance(obs, dict) and env.observation_space.contains(obs)
    flat = gym.make("EKFSLAM-v0")
    flat_obs, _ = flat.reset(seed=1)
    np.testing.assert_array_equal(np.concatenate(list(obs.values())), flat_obs)
    from gymnasium.utils.env_checker import check_env

    check_env(env.unwrapped, skip_render_check=True)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_same_seed_gives_bit_identical_rollouts(env_id):
    assert rollout(gym.make(env_id), 3, 150) == rollout(gym.make(env_id), 3, 150)
    assert rollout(gym.make(env_id), 3, 20) != rollout(gym.make(env_id), 4, 20)


def test_rollouts_are_identical_in_two_processes():
    code = (
        "import hashlib, gymnasium as gym, numpy as np, ekfslam_gym;"
        "env = gym.make('EKFSLAM-v0'); obs, _ = env.reset(seed=7); rng = np.random.default_rng(1); h = hashlib.sha256();"
        "exec('for _ in range(200):\\n o, r, te, tr, i = env.step(rng.uniform(-1, 1, 2).astype(np.float32))\\n"
        " h.update(o.tobytes()); h.update(np.float64(r).tobytes())');"
        "print(h.hexdigest())"
    )
    digests = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
               for _ in range(2)}  # fmt: skip
    assert len(digests) == 1 and len(next(iter(digests)).strip()) == 64


def test_pickle_mid_episode_continues_identically():
    env = EKFSLAMEnv()
    env.reset(seed=5)
    rng = np.random.default_rng(2)
    for _ in range(60):
        env.step(rng.uniform(-1, 1, 2))
    clone = pickle.loads(pickle.dumps(env))
    actions = rng.uniform(-1, 1, (100, 2))
    for action in actions:
        a = env.step(action)
        b = clone.step(action)
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:4] == b[1:4]


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


@pytest.mark.parametrize(
    "bad", [np.array([np.nan, 0.0]), np.array([0.0, np.inf]), np.zeros(3), np.zeros((1, 2))]
)
def test_bad_actions_raise_and_change_nothing(bad):
    env = EKFSLAMEnv()
    env.reset(seed=0)
    env.step(np.array([0.5, 0.2]))
    before = pickle.dumps((env.filter.mean.copy(), env.filter.cov.copy(), env.world.pose, env.elapsed_steps))
    with pytest.raises(ValueError):
        env.step(bad)
    assert (
        pickle.dumps((env.filter.mean.copy(), env.filter.cov.copy(), env.world.pose, env.elapsed_steps))
        == before
    )


def test_out_of_range_actions_are_clipped():
    a, b = EKFSLAMEnv(), EKFSLAMEnv()
    a.reset(seed=4)
    b.reset(seed=4)
    for _ in range(10):
        ra = a.step(np.array([7.0, -3.0]))
        rb = b.step(np.array([1.0, -1.0]))
        np.testing.assert_array_equal(ra[0], rb[0])


def test_step_before_reset_is_an_error():
    with pytest.raises(gym.error.ResetNeeded):
        EKFSLAMEnv().step(np.zeros(2))


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


def test_vector_envs_autoreset_reinitialises_the_belief():
    from gymnasium.vector import AutoresetMode

    envs = gym.make_vec("EKFSLAM-v0", num_envs=2, vectorization_mode="sync", max_episode_steps=5,
                        vector_kwargs={"autoreset_mode": AutoresetMode.NEXT_STEP})  # fmt: skip
    _, info0 = envs.reset(seed=[1, 2])
    for _ in range(5):
        _, _, _, truncated, info = envs.step(np.zeros((2, 2), dtype=np.float32))
    assert truncated.all()
    _, _, _, _, info = envs.step(np.zeros((2, 2), dtype=np.float32))  # the autoreset step
    for i, sub in enumerate(envs.envs):
        ekf = sub.unwrapped.filter
        assert sub.unwrapped.elapsed_steps == 0 and info["step"][i] == 0
        assert sub.unwrapped.config.max_episode_steps == 5 and sub.spec.max_episode_steps == 5
        assert info["log_det"][i] == pytest.approx(np.linalg.slogdet(ekf.cov)[1], abs=1e-9)
        assert info["log_det"][i] > info0["log_det"][i] - 50  # a fresh belief, not the 5-step-old one
        assert ekf.observed.sum() == info["landmarks_seen"][i]
    envs.close()


def test_subproc_vec_env_runs():
    sb3_vec = pytest.importorskip("stable_baselines3.common.vec_env")
    from stable_baselines3.common.env_util import make_vec_env

    venv = make_vec_env("ekfslam_gym:EKFSLAM-v0", n_envs=2, seed=0, vec_env_cls=sb3_vec.SubprocVecEnv,
                        env_kwargs={"max_episode_steps": 4})  # fmt: skip
    obs = venv.reset()
    assert obs.shape == (2, 164)
    ended = []
    for _ in range(6):
        obs, rewards, dones, infos = venv.step(np.zeros((2, 2), dtype=np.float32))
        ended.append(dones.copy())
        assert np.isfinite(obs).all() and np.isfinite(rewards).all()
    assert np.array_equal(np.array(ended).any(axis=1), [False, False, False, True, False, False])
    assert infos[0]["step"] == 2  # counting again in the new episode
    venv.close()


def test_pose_anees_under_random_driving_is_consistent():
    """50 seeded random drives: the simulator's odometry noise and the filter's motion noise agree."""
    runs, steps = 50, 200
    nees = np.zeros((runs, steps))
    for run in range(runs):
        env = EKFSLAMEnv(max_episode_steps=steps)
        env.reset(seed=100 + run)
        rng = np.random.default_rng(run)
        action = rng.uniform(-1, 1, 2)
        for t in range(steps):
            if t % 10 == 0:
                action = rng.uniform(-1, 1, 2)
            *_, info = env.step(action)
            nees[run, t] = info["pose_nees"]
    anees = nees.mean(axis=0)
    low, high = stats.chi2.ppf([0.025, 0.975], 3 * runs) / runs
    inside = np.mean((anees >= low) & (anees <= high))
    assert inside >= 0.75, f"{inside:.0%} of steps inside [{low:.2f}, {high:.2f}], mean {anees.mean():.2f}"
    assert 2.4 <= anees.mean() <= 3.6


def test_readings_never_cross_a_wall():
    from ekfslam_gym.sim.geometry import segment_blocked

    env = EKFSLAMEnv(world={"layout": "rooms"})
    env.reset(seed=3)
    rng = np.random.default_rng(0)
    layout = env.world.layout
    count = 0
    for _ in range(300):
        *_, info = env.step(rng.uniform(-1, 1, 2))
        x, y, _ = info["true_pose"]
        for j in info["readings"].ids:
            lx, ly = layout.landmarks[j]
            assert not segment_blocked(x, y, lx, ly, layout.walls, layout.wall_radius)
            count += 1
    assert count > 50


def test_filter_failure_terminates_without_raising(monkeypatch):
    """The filter signals a numerical failure with ``FilterDivergedError`` (its public contract: an innovation
    covariance or Sigma that loses positive definiteness raises it); the env ends the episode and reports it
    instead of raising."""
    from ekfslam_gym.filter.ekf import FilterDivergedError

    env = EKFSLAMEnv()
    env.reset(seed=0)

    def diverge(*args, **kwargs):
        raise FilterDivergedError("innovation covariance is not positive definite")

    monkeypatch.setattr(env.filter, "update", diverge)
    _, reward, terminated, truncated, info = env.step(np.zeros(2))
    assert terminated and not truncated and info["filter_failed"] and reward == 0.0
    assert all(value == 0.0 for value in info["reward_terms"].values())


@pytest.mark.slow
def test_covariance_stays_symmetric_positive_definite_over_100k_random_steps():
    env = EKFSLAMEnv(max_episode_steps=100_000, done_std=0.0)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (100_000, 2))
    for t, action in enumerate(actions):
        _, _, terminated, truncated, info = env.step(action)
        assert not info["filter_failed"]
        if t % 20_000 == 0 or t == len(actions) - 1:
            cov = env.filter.cov
            assert np.array_equal(cov, cov.T)
            assert np.all(np.isfinite(cov)) and np.linalg.eigvalsh(cov)[0] > 0
            assert info["log_det"] == pytest.approx(
                np.linalg.slogdet(cov)[1], abs=1e-8 * max(1, abs(info["log_det"]))
            )
    assert truncated


def test_rgb_array_render_is_a_non_blank_frame():
    pytest.importorskip("pygame")
    env = gym.make("EKFSLAM-v0", render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.array([0.5, 0.3]))
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.shape == (640, 640, 3)
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 5
    env.close()


def test_observations_stay_inside_the_space_and_are_finite():
    env = EKFSLAMEnv(world={"layout": "loop"})
    obs, _ = env.reset(seed=9)
    rng = np.random.default_rng(9)
    for _ in range(300):
        obs, *_ = env.step(rng.uniform(-1, 1, 2))
        assert env.observation_space.contains(obs) and np.isfinite(obs).all()
    window = obs[-106:-25].reshape(9, 9)
    assert window.max() == 1.0 and window.min() == 0.0  # some of the world looked at, some not yet


def test_docs_page_is_generated_from_the_current_docstring():
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "docs" / "generate.py"
    result = subprocess.run([sys.executable, str(script), "--check"], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr


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


def test_coverage_window_is_robot_centred_and_turns_with_the_heading():
    from ekfslam_gym.envs.kernels import mark_coverage
    from ekfslam_gym.envs.observation import make_memory

    env = EKFSLAMEnv(world={"layout_kwargs": {"width": 40.0, "height": 40.0}})
    obs, _ = env.reset(seed=0)
    grid = env.config.observation.grid
    window = env.observation_layout.part(obs, "coverage").reshape(grid, grid)
    pose = env.filter.pose
    bounds, memory_now = env.bounds, env.coverage_memory
    # Rebuild the memory from the one pose the sensor has looked from, and read the window by hand.
    memory = make_memory(bounds, 0.5)
    mark_coverage(memory, np.array(pose), bounds, 0.5, env.config.sensor.max_range, env.config.sensor.fov)
    assert np.array_equal(memory, memory_now)
    centre = grid // 2
    assert window[centre, centre + 2] == 1.0  # 4 m straight ahead: inside the 6 m, 180 degree footprint
    ahead_left = pose[:2] + 4.0 * np.array([np.cos(pose[2] + 0.5), np.sin(pose[2] + 0.5)])
    assert memory_now[int((ahead_left[1] - bounds[1]) / 0.5), int((ahead_left[0] - bounds[0]) / 0.5)]
    behind = pose[:2] - 4.0 * np.array([np.cos(pose[2]), np.sin(pose[2])])
    inside = bounds[0] < behind[0] < bounds[2] and bounds[1] < behind[1] < bounds[3]
    assert window[centre, centre - 2] == (0.0 if inside else 1.0)  # behind: not looked at (or outside)


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


def test_coarse_window_holds_the_fraction_looked_at_and_can_be_disabled():
    env = EKFSLAMEnv()
    obs, _ = env.reset(seed=2)
    coarse = obs[-25:].reshape(5, 5)
    assert coarse.min() >= 0.0 and coarse.max() <= 1.0
    assert np.any((coarse > 0.0) & (coarse < 1.0))  # partly looked-at cells are fractions, not flags
    assert (
        coarse[0].min() == 1.0 or coarse[:, 0].min() == 1.0 or coarse[-1].min() == 1.0
    )  # 20 m reaches outside
    plain = EKFSLAMEnv(observation={"coarse_grid": 0})
    assert plain.observation_space.shape == (139,)
    np.testing.assert_array_equal(plain.reset(seed=2)[0], obs[:-25])


# ---------------------------------------------------------------------------------------- observation layout
@pytest.mark.parametrize(
    "observation, n_beams",
    [({}, 16), ({"k_nearest": 3, "grid": 5, "coarse_grid": 3}, 7), ({"kind": "dict", "coarse_grid": 0}, 16)],
)
def test_observation_layout_is_where_the_spaces_and_the_kernel_put_each_part(observation, n_beams):
    from ekfslam_gym.envs.kernels import fill_observation
    from ekfslam_gym.envs.observation import (
        LANDMARK_FEATURES,
        PARTS,
        ObservationLayout,
        observation_constants,
    )

    env = EKFSLAMEnv(observation=observation, sensor={"n_beams": n_beams})
    cfg = env.config
    layout = env.observation_layout
    assert layout == ObservationLayout.from_config(cfg.observation, cfg.sensor)
    # The slices tile the vector in PARTS order; the offsets say the same, absent parts being empty spans.
    present = [name for name in PARTS if name in layout.slices]
    assert list(layout.slices) == present == list(layout.sizes)
    assert ("coverage_coarse" in present) == (cfg.observation.coarse_grid > 0)
    stops = [0] + [layout.slices[name].stop for name in present]
    assert [layout.slices[name].start for name in present] == stops[:-1] and stops[-1] == layout.size
    for i, name in enumerate(PARTS):
        span = layout.offsets[i + 1] - layout.offsets[i]
        assert span == (layout.sizes[name] if name in present else 0)
    assert layout.sizes["landmarks"] == LANDMARK_FEATURES * cfg.observation.k_nearest
    assert layout.sizes["scan"] == n_beams and layout.sizes["coverage"] == cfg.observation.grid**2
    # The spaces are the layout's.
    space = env.observation_space
    if cfg.observation.kind == "dict":
        assert sorted(space.spaces) == sorted(present)  # gymnasium sorts a Dict's keys
        assert all(space[name].shape == (layout.sizes[name],) for name in present)
    else:
        assert space.shape == (layout.size,)

    obs, _ = env.reset(seed=6)
    for _ in range(20):
        obs, *_ = env.step(np.array([0.6, 0.4]))
    flat = np.concatenate([obs[name] for name in present]) if isinstance(obs, dict) else obs
    part = {name: layout.part(obs, name) for name in present}
    np.testing.assert_array_equal(flat[layout.slices["scan"]], part["scan"])
    # What the kernel wrote where the layout says: the scan, the pose, the time left, the landmark slots.
    scan = np.minimum(env.world.scan() / cfg.sensor.scan_max_range, 1.0).astype(np.float32)
    np.testing.assert_array_equal(part["scan"], scan)
    pose = env.filter.pose
    np.testing.assert_allclose(part["pose"][2:], [np.sin(pose[2]), np.cos(pose[2])], atol=1e-6)
    np.testing.assert_allclose(part["pose_cov"], np.log(np.diag(env.filter.pose_cov)) / 10, atol=1e-5)
    assert part["globals"][1] == pytest.approx(env.filter.observed.mean())
    assert part["globals"][2] == pytest.approx(1.0 - 20 / cfg.max_episode_steps)
    slots = part["landmarks"].reshape(-1, LANDMARK_FEATURES)
    assert slots[:, 0].sum() == min(env.filter.observed.sum(), cfg.observation.k_nearest)
    # Every entry is written: the kernel on a NaN-filled vector reproduces the observation exactly.
    ekf = env.filter
    out = np.full(layout.size, np.nan, dtype=np.float32)
    fill_observation(
        out, layout.offsets, observation_constants(cfg.observation, cfg.sensor), ekf.mean, ekf.cov,
        ekf.observed, ekf.log_det, ekf.pose_cov_given_map, env.world.scan(), env.coverage_memory, env.bounds,
        1.0 - 20 / cfg.max_episode_steps,
    )  # fmt: skip
    np.testing.assert_array_equal(out, flat)


def test_agents_read_the_scan_through_the_env_layout():
    from ekfslam_gym.agents.base import wall_scan

    for observation in ({"coarse_grid": 0, "k_nearest": 2}, {"kind": "dict"}):
        env = EKFSLAMEnv(observation=observation, sensor={"n_beams": 9})
        obs, _ = env.reset(seed=1)
        truth = np.minimum(env.world.scan(), env.config.sensor.scan_max_range)
        np.testing.assert_allclose(wall_scan(env, obs), truth, rtol=1e-6)


def test_layout_rejects_bad_sizes():
    from ekfslam_gym.envs.observation import ObservationLayout

    with pytest.raises(ValueError, match="n_beams"):
        ObservationLayout(8, 0, 9)
    with pytest.raises(ValueError, match="kind"):
        ObservationLayout(8, 16, 9).space("image")


# ---------------------------------------------------------------------------------------- reward hooks, access
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


def test_public_views_for_agents_are_read_only_and_need_a_reset():
    env = EKFSLAMEnv()
    with pytest.raises(gym.error.ResetNeeded):
        env.bounds  # noqa: B018
    env.reset(seed=0)
    assert env.elapsed_steps == 0
    env.step(np.zeros(2))
    assert env.elapsed_steps == 1
    np.testing.assert_array_equal(env.bounds, env.world.layout.bounds)
    for view in (env.bounds, env.coverage_memory, env.true_landmarks):
        with pytest.raises(ValueError):
            view[0] = 1.0


# ---------------------------------------------------------------------------------------- the step limit
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


@pytest.mark.parametrize("env_id", [i for i in ENV_IDS if i.endswith("-v0")])  # v1: tests/envs/test_v1_episode.py
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
