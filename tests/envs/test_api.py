"""The envs' API over the registry: checkers, make, determinism, pickling, bad actions, vector envs, views."""

import pickle
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401  (registers the envs)
from ekfslam_gym.envs import EKFSLAMEnv
from tests.envs.helpers import ENV_IDS, OBSERVATIONS, rollout


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


def test_observations_stay_inside_the_space_and_are_finite():
    env = EKFSLAMEnv(world={"layout": "loop"})
    obs, _ = env.reset(seed=9)
    rng = np.random.default_rng(9)
    for _ in range(300):
        obs, *_ = env.step(rng.uniform(-1, 1, 2))
        assert env.observation_space.contains(obs) and np.isfinite(obs).all()
    window = obs[-106:-25].reshape(9, 9)
    assert window.max() == 1.0 and window.min() == 0.0  # some of the world looked at, some not yet


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
