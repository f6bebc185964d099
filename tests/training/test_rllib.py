"""EKFSLAM-v0 under RLlib's PPO (new API stack): one training iteration.

RLlib pins its own gymnasium (Ray 2.60: 1.2.2), so it lives in the ``rllib`` extra and CI runs this file in an
environment of its own (``make test-rllib``); where RLlib is not installed the test skips.
"""

from __future__ import annotations

import math

import pytest

pytest.importorskip("ray.rllib")


def make_env(env_config: dict):
    import gymnasium as gym

    import ekfslam_gym  # noqa: F401  (registers the ids in RLlib's env runners)

    return gym.make("EKFSLAM-v0", max_episode_steps=int(env_config["max_episode_steps"]))


def test_one_rllib_ppo_iteration_trains_on_the_env():
    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)
    try:
        register_env("ekfslam", make_env)
        config = (
            PPOConfig()
            .environment("ekfslam", env_config={"max_episode_steps": 100})
            .env_runners(num_env_runners=0, rollout_fragment_length=200)
            .training(train_batch_size_per_learner=200, minibatch_size=100, num_epochs=1, lr=3e-4)
            .debugging(seed=0)
        )
        algo = config.build_algo()
        before = algo.get_module().get_state()
        result = algo.train()
        after = algo.get_module().get_state()
        algo.stop()
    finally:
        ray.shutdown()
    assert result["training_iteration"] == 1
    assert result["env_runners"]["num_env_steps_sampled_lifetime"] >= 200
    assert math.isfinite(result["env_runners"]["episode_return_mean"])  # two 100-step episodes ended
    changed = [k for k in before if not (before[k] == after[k]).all()]
    assert changed, "one PPO update changed no weight"
