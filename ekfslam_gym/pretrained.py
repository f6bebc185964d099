"""Saved policies with the env they were trained on: the shipped ones in one line, and any saved model's env for
plain stable-baselines3 use.

A model saved by the trainer keeps its env id and settings in the record beside it (``<model>_config.yaml``);
those settings (the action interface, the observation, the step limit) decide the spaces the policy was built
for, so the env comes from the record::

    import ekfslam_gym

    agent = ekfslam_gym.load_pretrained("EKFSLAM-Large-v0")   # the shipped policy, an Agent
    env = agent.make_env()                                    # its env: obs, _ = env.reset(seed=0) ...

    from stable_baselines3 import PPO
    venv = ekfslam_gym.make_env_for_model("run/model.zip")    # the record's env, VecNormalize statistics loaded
    model = ekfslam_gym.load_model("run/model.zip")           # PPO.load, safe outside a checkout
    action, _ = model.predict(venv.reset(), deterministic=True)

Needs the ``train`` extra (stable-baselines3, torch).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .packaged import shipped_model

DEFAULT_ENV_ID = "EKFSLAM-v0"
"""The env of agents that name none (no training record)."""


def shipped_policy_file(env_id: str) -> Path:
    """The shipped policy that serves ``env_id``: its own file (``ppo_<env_id>.zip``), else, for a v1 layout id
    (``ekfslam_gym.envs.presets.GENERALIST_IDS``), the generalist's, ``ppo_EKFSLAM-Mix-v1.zip``: one policy for
    every layout. ValueError naming the shipped ones otherwise."""
    from .envs.presets import GENERALIST_IDS, MIX_ID

    env_id = env_id.split(":")[-1]
    try:
        return shipped_model(env_id)
    except ValueError:
        if env_id not in GENERALIST_IDS:
            raise
    return shipped_model(MIX_ID)


def load_pretrained(env_id: str = "EKFSLAM-v0", **agent_kwargs: Any) -> Any:
    """The shipped policy for ``env_id`` (``shipped_policy_file``: the generalist for a v1 layout id) as a
    ``PPOAgent`` (deterministic; ``agent_kwargs`` go to it), its env settings in ``trained_env_id`` /
    ``trained_env_kwargs`` and its env from ``agent.make_env()``."""
    from ekfslam_gym.agents.ppo import PPOAgent

    return PPOAgent(shipped_policy_file(env_id), **agent_kwargs)


def model_env(path: str | Path) -> tuple[str, dict[str, Any]]:
    """(env id, env settings) from the training record beside the saved model at ``path``; ValueError without
    one."""
    from ekfslam_gym.artefacts import RECORD_FILE, RECORD_SUFFIX, model_paths, record_beside

    zip_path, _ = model_paths(path)
    record = record_beside(zip_path)
    if record is None or not record.env_id:
        raise ValueError(
            f"no training record naming the env beside {zip_path} (<model>{RECORD_SUFFIX} or {RECORD_FILE})"
        )
    return record.env_id, dict(record.env_kwargs or {})


def make_env_for_model(
    path: str | Path, env_kwargs: Mapping[str, Any] | None = None, *, n_envs: int = 1, seed: int | None = None
) -> Any:
    """A stable-baselines3 VecEnv of the env the model at ``path`` was trained on (its record's id and settings,
    ``env_kwargs`` merged on top section by section), wrapped in its saved VecNormalize statistics, frozen
    (no updates, rewards left raw), when the model has them: what ``model.predict`` expects to see."""
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    from ekfslam_gym.artefacts import model_paths
    from ekfslam_gym.evaluation.rollout import make_env, merge_env_kwargs

    env_id, trained = model_env(path)
    settings = merge_env_kwargs(trained, env_kwargs)
    venv = make_vec_env(lambda: make_env(env_id, settings), n_envs=n_envs, seed=seed)
    _, stats = model_paths(path)
    if stats.is_file():
        venv = VecNormalize.load(str(stats), venv)
        venv.training = False
        venv.norm_reward = False
    return venv


def resolve_env_id(agents: Sequence[Any], env_id: str | None = None, force: bool = False) -> str:
    """The env to run ``agents`` on: ``env_id`` when given, else the one their training records name
    (``trained_env_id``; one for all), else ``DEFAULT_ENV_ID``. ValueError when agents were trained on different
    envs and none is given, or when ``env_id`` is not one an agent was trained for (its own; for a policy trained
    on ``EKFSLAM-Mix-v1`` every v1 layout id, ``presets.trained_for``) and not ``force``d (then a warning says
    so)."""
    trained = {a: str(a.trained_env_id) for a in agents if getattr(a, "trained_env_id", None)}
    if env_id is None:
        ids = sorted({t.split(":")[-1] for t in trained.values()})
        if len(ids) > 1:
            raise ValueError(f"the models were trained on different envs ({', '.join(ids)}); give --env-id "
                             "(and --force to run them off their own)")  # fmt: skip
        return ids[0] if ids else DEFAULT_ENV_ID
    from .envs.presets import trained_for

    for agent, trained_id in trained.items():
        if env_id.split(":")[-1] not in trained_for(trained_id):
            if not force:
                raise ValueError(f"{agent!r} was trained on {trained_id}, not {env_id}: leave out --env-id to "
                                 f"evaluate it on {trained_id}, or add --force")  # fmt: skip
            warnings.warn(f"{agent!r} was trained on {trained_id}, evaluated on {env_id}", stacklevel=2)
    return env_id
