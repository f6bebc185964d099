"""A PPO policy trained by ``train.py``, loaded from its saved SB3 model, acting deterministically.

The algorithm is the run's ``algo`` (``ALGOS``, rl-zoo3's names): ``ppo`` (stable-baselines3's PPO, the default)
or ``ppo_lstm`` (sb3-contrib's RecurrentPPO), read from the trainer's record beside the model (else from the
policy class saved in the zip). A recurrent policy carries its LSTM state from one ``act`` to the next and
starts every episode (``reset``) from a fresh one, as sb3-contrib's ``predict(state, episode_start)`` expects.

File convention shared with the trainer (``ekfslam_gym.artefacts`` names the files): the model is
``<model>.zip`` and, when observations were normalised during training, the VecNormalize statistics are
``<model>_vecnormalize.pkl`` beside it. Without those
statistics a policy trained on normalised observations would see inputs on the wrong scale, so they are
loaded whenever the file exists (and can be required with ``require_vecnormalize``).

The trainer also writes its record (env id and config entry, with its ``env_kwargs``: ``RunRecord``) beside
every model; when it is there the agent exposes the env it was trained on (``trained_env_id``,
``trained_env_kwargs``): the evaluator runs it there unless told otherwise, and ``make_env()`` builds that env.
``load_model`` loads a saved model without importing the module its pickled ``policy_kwargs`` name (a model
trained in a checkout names the top-level ``agents`` package, which an installed wheel does not have): the
``policy_kwargs`` are rebuilt from the record instead.

stable-baselines3 is in the ``train`` extra: it is imported only when a model is loaded.
"""

from __future__ import annotations

import json
import pickle
import zipfile
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from ekfslam_gym.artefacts import RunRecord, model_paths, record_beside

from .base import ActionKind, Agent

# rl-zoo3's algorithm names -> (module, class); a config's train_settings choose one with ``algo``.
ALGOS: dict[str, tuple[str, str]] = {
    "ppo": ("stable_baselines3", "PPO"),
    "ppo_lstm": ("sb3_contrib", "RecurrentPPO"),
}


def algo_class(algo: str = "ppo") -> Any:
    """The SB3 class of the algorithm named ``algo`` in ``ALGOS`` (imported only now)."""
    if algo not in ALGOS:
        raise ValueError(f"algo must be one of {sorted(ALGOS)}, got {algo!r}")
    module, name = ALGOS[algo]
    try:
        imported = __import__(module, fromlist=[name])
    except ImportError as error:  # pragma: no cover - depends on the installed extras
        raise ImportError(
            f"algo {algo} needs {module.replace('_', '-')} and torch: pip install 'ekfslam-gym[train]'"
        ) from error
    return getattr(imported, name)


def saved_algo(zip_path: str | Path, record: RunRecord | None = None) -> str:
    """The ``algo`` a saved model was trained with: the trainer's record (``entry.algo``, absent = ``ppo``), or
    without one the saved policy class (sb3-contrib's recurrent policies are ``ppo_lstm``)."""
    if record is not None and record.entry:
        return record.algo
    try:
        with zipfile.ZipFile(zip_path) as archive:
            data = json.loads(archive.read("data"))
        module = str(data.get("policy_class", {}).get("__module__", ""))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile):
        return "ppo"
    return "ppo_lstm" if module.startswith("sb3_contrib.common.recurrent") else "ppo"


def load_vecnormalize(path: str | Path) -> Any:
    """VecNormalize statistics saved by ``VecNormalize.save``, frozen for evaluation (no updates, rewards
    left raw). Unpickled without a venv: only ``normalize_obs`` is used."""
    with open(path, "rb") as handle:
        stats = pickle.load(handle)
    stats.training = False
    stats.norm_reward = False
    return stats


# policy_kwargs entries that name a class or function, resolved from a dotted name (``resolve_policy_kwargs``).
CLASS_KWARGS = ("features_extractor_class", "activation_fn", "optimizer_class")


def import_dotted(name: str) -> Any:
    """The object a dotted name points at (``ekfslam_gym.agents.extractors.BeliefCNN``; ``nn.X`` is ``torch.nn.X``)."""
    import importlib

    if name.startswith("nn."):
        name = "torch." + name
    module, _, attribute = name.rpartition(".")
    if not module:
        raise ValueError(f"{name!r} is not a dotted name (module.Class)")
    try:
        return getattr(importlib.import_module(module), attribute)
    except (ImportError, AttributeError) as error:
        raise ValueError(f"cannot import {name!r}: {error}") from None


def resolve_policy_kwargs(kwargs: dict[str, Any] | None) -> dict[str, Any] | None:
    """``policy_kwargs`` with the class names of ``CLASS_KWARGS`` given as dotted strings imported (the trainer
    builds a policy with them, and ``load_model`` rebuilds a saved one's)."""
    if kwargs is None:
        return None
    return {k: import_dotted(v) if k in CLASS_KWARGS and isinstance(v, str) else v for k, v in kwargs.items()}


def load_model(path: str | Path, *, device: str = "cpu", algo: str | None = None) -> Any:
    """The SB3 model saved at ``path`` (``<model>.zip``, with or without ``.zip``), its ``policy_kwargs`` rebuilt
    from the training record beside it when there is one (so loading never imports the module the pickle
    names). ``algo`` (``ALGOS``) defaults to the record's, else the saved policy class's."""
    zip_path, _ = model_paths(path)
    if not zip_path.is_file():
        raise FileNotFoundError(f"no saved model at {zip_path}")
    record = record_beside(zip_path)
    recorded = record.policy_kwargs if record is not None else None
    custom: dict[str, Any] = {}
    if recorded is not None:
        custom["policy_kwargs"] = resolve_policy_kwargs(recorded)
    return algo_class(algo or saved_algo(zip_path, record)).load(
        zip_path, device=device, custom_objects=custom or None
    )


class PPOAgent(Agent):
    """Acts with a saved SB3 PPO or RecurrentPPO policy (deterministic: the mean action), observations normalised
    as in training; a recurrent policy's LSTM state is carried across steps and reset at every episode start.

    Args:
        model_path: ``<model>.zip`` (or the path without ``.zip``); loads ``<model>_vecnormalize.pkl`` beside
            it if present.
        model: an already loaded model instead (e.g. the trainer's, in memory); ``vecnormalize`` then gives
            its statistics, if any.
        deterministic: act with the mean action (the default for evaluation).
        device: torch device for the policy.
        require_vecnormalize: raise if the statistics file is missing rather than act unnormalised.
        algo: ``ppo`` or ``ppo_lstm`` (``ALGOS``) for ``model_path``; None reads it beside the model.
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
        algo: str | None = None,
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
            record = record_beside(zip_path)
            model = load_model(zip_path, device=device, algo=algo)
            if stats_path.is_file():
                vecnormalize = load_vecnormalize(stats_path)
            elif require_vecnormalize:
                raise FileNotFoundError(f"no VecNormalize statistics at {stats_path}")
            self.model_path = zip_path
            if record is not None:
                self.trained_env_id = record.env_id
                self.trained_env_kwargs = record.env_kwargs
        self.model = model
        self.vecnormalize = vecnormalize
        self.action_kind = trained_action_kind(model.action_space, self.trained_env_kwargs)
        self.recurrent = is_recurrent(model.policy)
        self._state: Any = None
        self._episode_start = np.ones((1,), dtype=bool)

    def make_env(self, env_kwargs: dict[str, Any] | None = None, **make_kwargs: Any) -> gym.Env:
        """The env the policy was trained on (its record's id and settings, ``env_kwargs`` merged on top section
        by section), for ``run_episode`` or a loop of one's own: ``obs, _ = env.reset(seed=s)``,
        ``agent.reset(env, s)``, then ``env.step(agent.act(obs))``. ``make_kwargs`` go to
        ``evaluation.rollout.make_env`` (``max_episode_steps``, ``render_mode``)."""
        from ekfslam_gym.evaluation.rollout import make_env, merge_env_kwargs

        if self.trained_env_id is None:
            raise ValueError(f"{self!r} has no training record naming its env; build the env with gym.make")
        return make_env(
            self.trained_env_id, merge_env_kwargs(self.trained_env_kwargs, env_kwargs), **make_kwargs
        )

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        self._state = None  # a fresh LSTM state: zeros, and episode_start tells the policy so too
        self._episode_start = np.ones((1,), dtype=bool)
        expected = self.model.observation_space
        if _shapes(expected) != _shapes(env.observation_space):
            raise ValueError(
                f"the model was trained on observations {expected}, the env gives {env.observation_space}; "
                "evaluate it on the env id and config it was trained with"
            )

    def act(self, observation: Any) -> np.ndarray:
        if self.vecnormalize is not None and self.vecnormalize.norm_obs:
            observation = self.vecnormalize.normalize_obs(observation)
        if self.recurrent:
            action, self._state = self.model.predict(
                observation,
                state=self._state,
                episode_start=self._episode_start,
                deterministic=self.deterministic,
            )
            self._episode_start = np.zeros((1,), dtype=bool)
        else:
            action, _ = self.model.predict(observation, deterministic=self.deterministic)
        space = self.model.action_space
        if isinstance(space, gym.spaces.Discrete):  # action.kind primitives
            return np.int64(np.asarray(action).reshape(()))
        return np.clip(np.asarray(action, dtype=np.float32).reshape(space.shape), space.low, space.high)

    def __repr__(self) -> str:
        return f"PPOAgent(model_path={str(self.model_path)!r})"


def trained_action_kind(action_space: gym.Space, env_kwargs: dict[str, Any] | None) -> ActionKind | None:
    """The interface a saved policy acts in: primitives for a Discrete action space, else the ``action.kind``
    its training env's settings name; None when they do not (the env id's own interface)."""
    if isinstance(action_space, gym.spaces.Discrete):
        return ActionKind.PRIMITIVES
    action = (env_kwargs or {}).get("action")
    kind = action.get("kind") if isinstance(action, dict) else None
    return ActionKind(kind) if kind in ("velocity", "waypoint") else None


def is_recurrent(policy: Any) -> bool:
    """Whether ``policy`` is one of sb3-contrib's recurrent (RecurrentPPO) policies: they carry an LSTM state
    and read whole sequences; plain PPO policies do not."""
    return getattr(policy, "lstm_hidden_state_shape", None) is not None


def _shapes(space: gym.Space) -> Any:
    """A space's shape, or for a Dict its keys' shapes (so a missing belief image is noticed)."""
    if isinstance(space, gym.spaces.Dict):
        return {key: _shapes(sub) for key, sub in space.spaces.items()}
    return getattr(space, "shape", None)
