"""A PPO policy trained by ``train.py``, loaded from its saved SB3 model, acting deterministically.

File convention shared with the trainer: the model is ``<model>.zip`` and, when observations were normalised
during training, the VecNormalize statistics are ``<model>_vecnormalize.pkl`` beside it. Without those
statistics a policy trained on normalised observations would see inputs on the wrong scale, so they are
loaded whenever the file exists (and can be required with ``require_vecnormalize``).

The trainer also writes ``config.yaml`` (env id and config entry, with its ``env_kwargs``) beside every
model; when it is there the agent exposes the env it was trained on (``trained_env_id``,
``trained_env_kwargs``) so the evaluator can warn about evaluating it on a different one.

stable-baselines3 is in the ``train`` extra: it is imported only when a model is loaded.
"""

from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from .base import Agent

VECNORMALIZE_SUFFIX = "_vecnormalize.pkl"


def _import_ppo() -> Any:
    try:
        from stable_baselines3 import PPO
    except ImportError as error:  # pragma: no cover - depends on the installed extras
        raise ImportError(
            "the ppo agent needs stable-baselines3 and torch: pip install 'ekfslam-gym[train]'"
        ) from error
    return PPO


def model_paths(path: str | Path) -> tuple[Path, Path]:
    """(``<model>.zip``, ``<model>_vecnormalize.pkl``) for a model path given with or without ``.zip``."""
    path = Path(path)
    stem = path.with_suffix("") if path.suffix == ".zip" else path
    return stem.with_name(stem.name + ".zip"), stem.with_name(stem.name + VECNORMALIZE_SUFFIX)


def load_vecnormalize(path: str | Path) -> Any:
    """VecNormalize statistics saved by ``VecNormalize.save``, frozen for evaluation (no updates, rewards
    left raw). Unpickled without a venv: only ``normalize_obs`` is used."""
    with open(path, "rb") as handle:
        stats = pickle.load(handle)
    stats.training = False
    stats.norm_reward = False
    return stats


def training_record(zip_path: str | Path) -> dict[str, Any] | None:
    """The trainer's record of the model's run, parsed: ``<model>_config.yaml`` beside it, else the run folder's
    ``config.yaml``; None when there is none (or it is unreadable)."""
    zip_path = Path(zip_path)
    path = zip_path.with_name(zip_path.stem + "_config.yaml")
    if not path.is_file():
        path = zip_path.parent / "config.yaml"
    if not path.is_file():
        return None
    import yaml

    try:
        record = yaml.safe_load(path.read_text())
    except yaml.YAMLError:
        return None
    return record if isinstance(record, dict) else None


class PPOAgent(Agent):
    """Acts with a saved SB3 PPO policy (deterministic: the mean action), observations normalised as in training.

    Args:
        model_path: ``<model>.zip`` (or the path without ``.zip``); loads ``<model>_vecnormalize.pkl`` beside
            it if present.
        model: an already loaded model instead (e.g. the trainer's, in memory); ``vecnormalize`` then gives
            its statistics, if any.
        deterministic: act with the mean action (the default for evaluation).
        device: torch device for the policy.
        require_vecnormalize: raise if the statistics file is missing rather than act unnormalised.
    """

    name = "ppo"

    def __init__(
        self,
        model_path: str | Path | None = None,
        *,
        model: Any = None,
        vecnormalize: Any = None,
        deterministic: bool = True,
        device: str = "cpu",
        require_vecnormalize: bool = False,
    ) -> None:
        super().__init__()
        if (model_path is None) == (model is None):
            raise ValueError("give exactly one of model_path and model (the ppo agent needs --model PATH)")
        self.deterministic = deterministic
        self.model_path: Path | None = None
        self.trained_env_id: str | None = None
        self.trained_env_kwargs: dict[str, Any] | None = None
        if model_path is not None:
            zip_path, stats_path = model_paths(model_path)
            if not zip_path.is_file():
                raise FileNotFoundError(f"no saved model at {zip_path}")
            model = _import_ppo().load(zip_path, device=device)
            if stats_path.is_file():
                vecnormalize = load_vecnormalize(stats_path)
            elif require_vecnormalize:
                raise FileNotFoundError(f"no VecNormalize statistics at {stats_path}")
            self.model_path = zip_path
            record = training_record(zip_path)
            if record is not None:
                self.trained_env_id = record.get("env_id")
                entry = record.get("entry")
                if isinstance(entry, dict) and isinstance(entry.get("env_kwargs"), dict):
                    self.trained_env_kwargs = entry["env_kwargs"]
        self.model = model
        self.vecnormalize = vecnormalize

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        expected = self.model.observation_space
        if getattr(expected, "shape", None) != getattr(env.observation_space, "shape", None):
            raise ValueError(
                f"the model was trained on observations {expected}, the env gives {env.observation_space}; "
                "evaluate it on the env id and config it was trained with"
            )

    def act(self, observation: Any) -> np.ndarray:
        if self.vecnormalize is not None and self.vecnormalize.norm_obs:
            observation = self.vecnormalize.normalize_obs(observation)
        action, _ = self.model.predict(observation, deterministic=self.deterministic)
        space = self.model.action_space
        if isinstance(space, gym.spaces.Discrete):  # action.kind primitives
            return np.int64(np.asarray(action).reshape(()))
        return np.clip(np.asarray(action, dtype=np.float32).reshape(space.shape), space.low, space.high)

    def __repr__(self) -> str:
        return f"PPOAgent(model_path={str(self.model_path)!r})"
