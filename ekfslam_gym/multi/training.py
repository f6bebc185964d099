"""Shared-parameter PPO for the team env: one policy, every robot an independent sample of it.

The team env (a PettingZoo ``ParallelEnv``) becomes an SB3 ``VecEnv`` through SuperSuit's standard adapter:
``pettingzoo_env_to_vec_env_v1`` makes each robot one of the vector's envs (the robots share the policy, each
acting on its own observation: parameter sharing, Gupta, Egorov & Kochenderfer, AAMAS 2017, and Terry et al.'s
"Revisiting parameter sharing", 2020), and ``concat_vec_envs_v1`` stacks ``n_envs`` copies of the team. Then
``VecMonitor`` and ``VecNormalize`` (observations and rewards), as the single-robot recipes train.

The recipe is a YAML file (``configs/multi/ppo_team.yaml``): ``env_kwargs`` (``parallel_env``'s sections and
``n_robots``), ``n_envs``, ``n_timesteps`` (robot decisions, all robots counted), ``seed`` and PPO's keyword
arguments. A run writes into its folder ``model.zip``, ``model_vecnormalize.pkl``, ``config.yaml`` (the
recipe as run) and ``checkpoints/``; run again, it resumes from the newest checkpoint (its statistics beside
it). ``max_minutes`` stops a run early, saved, so it fits a time budget and can be resumed later.

    python -m ekfslam_gym.cli.team_train configs/multi/ppo_team.yaml runs/team3 [--max-minutes 35]
"""

from __future__ import annotations

import re
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .env import TeamSLAMEnv, parallel_env

VECNORMALIZE_SUFFIX = "_vecnormalize.pkl"
RECIPE_KEYS = {"env_kwargs", "n_envs", "n_timesteps", "seed", "ppo", "checkpoint_freq"}


def read_recipe(path: str | Path) -> dict[str, Any]:
    """The recipe at ``path``, checked: a mapping with ``RECIPE_KEYS`` only (``ppo`` PPO's keyword arguments)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"team recipe {path} does not exist")
    recipe = yaml.safe_load(path.read_text()) or {}
    if not isinstance(recipe, Mapping):
        raise ValueError(f"{path}: the top level must be a mapping")
    unknown = sorted(set(recipe) - RECIPE_KEYS)
    if unknown:
        raise ValueError(f"{path}: unknown keys {unknown}; known: {sorted(RECIPE_KEYS)}")
    return dict(recipe)


def team_vec_env(env_kwargs: Mapping[str, Any], n_envs: int, seed: int):
    """``n_envs`` copies of the team env as one SB3 VecEnv of n_envs x n_robots robots (SuperSuit), monitored;
    copy k's first reset is seeded ``seed + k``, later ones continue its own stream."""
    import supersuit as ss
    from stable_baselines3.common.vec_env import VecMonitor
    from supersuit.vector.sb3_vector_wrapper import SB3VecEnvWrapper

    class SeededSB3VecEnv(SB3VecEnvWrapper):
        """SuperSuit's SB3 adapter with SB3's ``seed``: SB3 seeds a VecEnv before its first reset, and the
        adapter (SuperSuit 3.11) passes the call to the underlying vector, which has no ``seed``."""

        _next_seed: int | None = None

        def seed(self, seed: int | None = None) -> list[int | None]:
            self._next_seed = seed
            return [seed] * self.num_envs

        def reset(self, seed: int | None = None, options: dict | None = None):
            seed, self._next_seed = (seed if seed is not None else self._next_seed), None
            observations, self.reset_infos = self.venv.reset(seed=seed, options=options)
            return observations

    team = parallel_env(**env_kwargs)
    vec = ss.pettingzoo_env_to_vec_env_v1(team)
    vec = SeededSB3VecEnv(ss.concat_vec_envs_v1(vec, n_envs, num_cpus=0, base_class="gymnasium"))
    vec.seed(seed)
    return VecMonitor(vec)


def _schedule(value: Any) -> Any:
    """rl-zoo3's ``lin_<x>``: a rate falling linearly from x to 0 over the run; numbers pass through."""
    if isinstance(value, str) and (match := re.fullmatch(r"lin_([0-9.eE+-]+)", value)):
        start = float(match.group(1))
        return lambda progress: progress * start
    return value


def _newest_checkpoint(folder: Path) -> Path | None:
    checkpoints = sorted(folder.glob("model_*_steps.zip"), key=lambda p: int(p.stem.split("_")[1]))
    return checkpoints[-1] if checkpoints else None


def train(recipe: Mapping[str, Any], out: str | Path, max_minutes: float | None = None) -> Path:
    """Train (or resume) the recipe's shared policy into folder ``out``; returns the saved model's path."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback, CallbackList, CheckpointCallback
    from stable_baselines3.common.vec_env import VecNormalize

    torch.set_num_threads(1)
    out = Path(out)
    (out / "checkpoints").mkdir(parents=True, exist_ok=True)
    (out / "config.yaml").write_text(yaml.safe_dump(dict(recipe), sort_keys=False))
    env_kwargs = dict(recipe.get("env_kwargs", {}))
    seed = int(recipe.get("seed", 0))
    vec = team_vec_env(env_kwargs, int(recipe.get("n_envs", 4)), seed)
    ppo_kwargs = {key: _schedule(value) for key, value in dict(recipe.get("ppo", {})).items()}
    checkpoint = _newest_checkpoint(out / "checkpoints")
    if checkpoint is not None:
        stats = checkpoint.with_name(checkpoint.stem.replace("model_", "model_vecnormalize_") + ".pkl")
        vec = VecNormalize.load(str(stats), vec)
        model = PPO.load(checkpoint, env=vec, device="cpu")
        print(f"resuming from {checkpoint} at {model.num_timesteps} steps", flush=True)
    else:
        vec = VecNormalize(vec, norm_obs=True, norm_reward=True, gamma=float(ppo_kwargs.get("gamma", 0.99)))
        model = PPO("MlpPolicy", vec, seed=seed, device="cpu", verbose=0, **ppo_kwargs)

    class Deadline(BaseCallback):
        """Stops training once ``max_minutes`` of wall time have passed (the run is saved and resumable)."""

        def __init__(self) -> None:
            super().__init__()
            self.start = time.monotonic()
            self.last_report = 0

        def _on_step(self) -> bool:
            if self.num_timesteps - self.last_report >= 20000:
                self.last_report = self.num_timesteps
                buffer = [e["r"] for e in self.model.ep_info_buffer]
                mean = float(np.mean(buffer)) if buffer else float("nan")
                minutes = (time.monotonic() - self.start) / 60
                print(f"{self.num_timesteps} steps, {minutes:.1f} min, episode return {mean:.1f}", flush=True)
            return max_minutes is None or time.monotonic() - self.start < 60.0 * max_minutes

    every = max(1, int(recipe.get("checkpoint_freq", 50000)) // vec.num_envs)
    checkpoints = CheckpointCallback(
        every, str(out / "checkpoints"), name_prefix="model", save_vecnormalize=True
    )
    total = int(recipe.get("n_timesteps", 500000))
    model.learn(
        total_timesteps=max(0, total - model.num_timesteps),
        callback=CallbackList([checkpoints, Deadline()]),
        reset_num_timesteps=checkpoint is None,
    )
    model.save(out / "model")
    vec.save(str(out / f"model{VECNORMALIZE_SUFFIX}"))
    model.save(out / "checkpoints" / f"model_{model.num_timesteps}_steps")
    vec.save(str(out / "checkpoints" / f"model_vecnormalize_{model.num_timesteps}_steps.pkl"))
    print(f"saved {out / 'model.zip'} after {model.num_timesteps} steps", flush=True)
    return out / "model.zip"


class TeamPolicy:
    """A trained shared policy acting for every robot of a team env: each robot's observation normalised by the
    run's statistics, then the policy's deterministic action."""

    def __init__(self, model_path: str | Path) -> None:
        import pickle

        from stable_baselines3 import PPO

        model_path = Path(model_path)
        # The schedules are pickled functions of the training run: acting needs none of them.
        custom = {"learning_rate": 0.0, "lr_schedule": lambda _: 0.0, "clip_range": lambda _: 0.0}
        self.model = PPO.load(model_path, device="cpu", custom_objects=custom)
        stats = model_path.with_name(model_path.stem + VECNORMALIZE_SUFFIX)
        self._normalize = None
        if stats.is_file():
            with stats.open("rb") as f:
                self._normalize = pickle.load(f)
        self.name = "team-ppo"

    def reset(self, team: TeamSLAMEnv, seed: int | None = None) -> None:
        """Nothing to reset: the policy is feed-forward."""

    def act(self, observations: Mapping[str, np.ndarray]) -> dict[str, int]:
        agents = list(observations)
        batch = np.stack([observations[a] for a in agents])
        if self._normalize is not None:
            batch = self._normalize.normalize_obs(batch)
        actions, _ = self.model.predict(batch, deterministic=True)
        return {agent: int(action) for agent, action in zip(agents, actions)}
