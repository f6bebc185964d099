"""Self-imitation demonstrations (an experiment, not shipped; docs/results.md, *Self-imitation*).

The trained policy drives ``k`` episodes per map: the first deterministic, the others with a sampled action at
a fraction ``eps`` of its decisions. Of each map's episodes the one best on both of issue 8's Large bars,
z = map_log_det / 150 + landmark_rmse / 0.034 (the reward curve's slope: 150 of log det per 0.034 m), is kept,
labelled with the policy's own actions, as expert iteration's improvement step (Anthony et al. 2017; self-
imitation, Oh et al. 2018). The file is a ``pretrain.path`` demonstrations file.

    python -m agents.self_imitation MODEL FIRST_SEED N K OUT.npz
"""

from __future__ import annotations

import json
import sys
from dataclasses import asdict
from typing import Any

import gymnasium as gym
import numpy as np
import torch as th

from agents.demonstrations import Demonstrations, save
from agents.ppo import PPOAgent
from ekfslam_gym.evaluation.episodes import run_episode

EPS = 0.25
ENV_KWARGS = {"action": {"kind": "primitives", "hold": 10}, "max_episode_steps": 100,
              "reward": {"collision": 5.0, "pose_variance": 8.0}}  # fmt: skip


class Recorder(gym.Wrapper):
    """Keeps the current episode's observations, actions, rewards and reward terms."""

    def reset(self, **kwargs: Any) -> Any:
        observation, info = self.env.reset(**kwargs)
        self.observations, self.actions, self.rewards, self.terms = [], [], [], []
        self.last = observation
        return observation, info

    def step(self, action: Any) -> Any:
        self.observations.append(self.last)
        self.actions.append(int(action))
        observation, reward, terminated, truncated, info = self.env.step(action)
        self.rewards.append(float(reward))
        self.terms.append(dict(info["reward_terms"]))
        self.last = observation
        return observation, reward, terminated, truncated, info


class Perturbed:
    """The deterministic policy, with the stochastic one's action at a fraction ``eps`` of the decisions."""

    name = "perturbed"

    def __init__(self, model: str, eps: float, rng: np.random.Generator) -> None:
        self.mean, self.sampled, self.eps, self.rng = (
            PPOAgent(model),
            PPOAgent(model, deterministic=False),
            eps,
            rng,
        )

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        self.mean.reset(env, seed)
        self.sampled.reset(env, seed)

    def act(self, observation: Any) -> np.int64:
        return (self.sampled if self.rng.random() < self.eps else self.mean).act(observation)


def collect(model: str, first: int, n: int, k: int, out: str) -> None:
    env = Recorder(gym.make("ekfslam_gym:EKFSLAM-Large-v0", **ENV_KWARGS))
    weights = asdict(env.unwrapped.config.reward)
    names = [name for name, weight in weights.items() if weight]
    mean, perturbed = PPOAgent(model), Perturbed(model, EPS, np.random.default_rng(first))
    observations, actions, rewards, episodes, seeds, log = [], [], [], [], [], []
    terms: dict[str, list[float]] = {name: [] for name in names}
    for i, seed in enumerate(range(first, first + n)):
        best = None
        for j in range(k):
            th.manual_seed(seed * 100 + j)
            metrics = run_episode(env, mean if j == 0 else perturbed, seed)
            z = metrics["map_log_det"] / 150 + metrics["landmark_rmse"] / 0.034
            if best is None or z < best[0]:
                best = (z, list(env.observations), list(env.actions), list(env.rewards), list(env.terms))
            log.append({"seed": seed, "j": j, "z": z, "map_log_det": metrics["map_log_det"],
                        "rmse": metrics["landmark_rmse"]})  # fmt: skip
        _, obs, acts, rews, steps = best
        observations += obs
        actions += acts
        rewards += rews
        episodes += [i] * len(acts)
        seeds.append(seed)
        for name in names:
            terms[name] += [step.get(name, 0.0) for step in steps]
    meta = {"env_id": "EKFSLAM-Large-v0", "env_kwargs": ENV_KWARGS, "planner": "self", "planner_kwargs": {},
            "driver": model, "reward_weights": weights, "self_imitation": {"k": k, "eps": EPS}}  # fmt: skip
    save(Demonstrations(np.stack(observations).astype(np.float32), np.array(actions, dtype=np.int64),
                        np.array(rewards), np.array(episodes), np.array(seeds), meta,
                        {name: np.array(v) for name, v in terms.items()}), out)  # fmt: skip
    with open(out.replace(".npz", "_log.json"), "w") as f:
        json.dump(log, f)


if __name__ == "__main__":
    collect(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5])
