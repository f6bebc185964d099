"""Shared by the env tests: the registered ids, the observations to check, a seeded rollout."""

import numpy as np

from ekfslam_gym.envs import PRESETS

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
