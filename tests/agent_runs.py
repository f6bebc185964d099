"""An agent's actions over one seeded episode of a registered env, for the agent tests."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import ekfslam_gym  # noqa: F401  (registers the env ids)


def agent_actions(agent, seed: int, steps: int, env_id: str = "EKFSLAM-v0", tries: int | None = None):
    """(actions (k, ...), truncated) of ``agent`` in ``env_id`` made with ``max_episode_steps=steps``, for up to
    ``tries`` steps (``steps`` by default; one more shows that the episode ended by itself)."""
    env = gym.make(env_id, max_episode_steps=steps)
    observation, _ = env.reset(seed=seed)
    agent.reset(env, seed=seed)
    actions, truncated = [], False
    for _ in range(steps if tries is None else tries):
        action = agent.act(observation)
        actions.append(action)
        observation, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    env.close()
    return np.array(actions), truncated
