"""Record the baselines' actions on a seeded episode, which ``tests/agents/test_golden_agents.py`` holds them to.

Run once before refactoring an agent: ``python tests/golden/record_agents.py`` writes ``agents.npz`` beside
this file (the first ``STEPS`` actions of each agent on EKFSLAM-v0 and EKFSLAM-Loop-v0, seed 7).
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

import ekfslam_gym  # noqa: F401  (registers the ids)

AGENT_NAMES = ("circle", "lawnmower", "greedy", "frontier")
ENV_IDS = ("EKFSLAM-v0", "EKFSLAM-Loop-v0")
STEPS = 120
SEED = 7
HERE = Path(__file__).resolve().parent
# The filter settings the recording was made with (the defaults then); the agents plan on the filter's belief.
PREVIOUS_FILTER = {"filter": {"motion_model": "odometry", "pose_prior": 1e-6}}


def actions(agent_name: str, env_id: str) -> np.ndarray:
    from ekfslam_gym.agents import make_agent

    env = gym.make(env_id, **PREVIOUS_FILTER)
    agent = make_agent(agent_name)
    obs, _ = env.reset(seed=SEED)
    agent.reset(env, seed=SEED)
    out = []
    for _ in range(STEPS):
        action = np.asarray(agent.act(obs), dtype=np.float32)
        out.append(action)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    env.close()
    return np.asarray(out)


def main() -> None:
    arrays = {f"{env_id}/{name}": actions(name, env_id) for env_id in ENV_IDS for name in AGENT_NAMES}
    np.savez_compressed(HERE / "agents.npz", **arrays)
    print(f"wrote {HERE / 'agents.npz'}")


if __name__ == "__main__":
    main()
