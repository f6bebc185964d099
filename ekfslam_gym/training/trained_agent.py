"""A new run that starts from a trained policy instead of fresh weights (``ekfslam-train --trained-agent MODEL``,
rl-zoo3's flag): a shipped policy fine-tuned on a user's own map, or a run trained on under another reward. The
weights, the optimiser state and the observation statistics come from the model; the rest (the env, the reward,
PPO's hyperparameters, the budget, the seed) from the config, as for any run. The command line also takes an env
id for MODEL, meaning its shipped policy (``ekfslam_gym.pretrained.shipped_policy_file``).

``check_trained_agent`` refuses, before the run folder is created, what could not continue the model: a missing
file, another algorithm, observation or action spaces the config's env does not have, normalisation on one side
only, a network of another shape (``policy_kwargs`` other than those in the model's record), and a ``pretrain``
stage (cloning a planner would overwrite the weights it starts from).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ekfslam_gym.artefacts import ModelFiles, record_beside

from .settings import SettingsError

FLAG = "--trained-agent"


def check_trained_agent(model: str | Path, env_id: str, entry: dict[str, Any]) -> tuple[Path, Path | None]:
    """Check that the saved model ``model`` (with or without ``.zip``) can start a run of ``entry`` on
    ``env_id``; returns its ``.zip`` and its normalisation statistics file, or None when it was trained without.
    Raises ``SettingsError`` naming what does not fit."""
    files = ModelFiles.of(model)
    path = files.zip
    if not path.is_file():
        raise SettingsError(f"{FLAG} {model}: no such model ({path} is not a file)")
    if entry["pretrain"] is not None:
        raise SettingsError(
            f"{FLAG} starts from a trained policy, and the config's pretrain stage would clone a planner over "
            "it: drop one of them (--hyperparams pretrain=null)"
        )
    record = record_beside(files.zip)
    if record is not None and record.entry and record.algo != entry["algo"]:
        raise SettingsError(f"{FLAG} {path}: the model was trained with algo {record.algo!r} and this config "
                            f"trains {entry['algo']!r}")  # fmt: skip
    if (
        record is not None
        and record.policy_kwargs is not None
        and record.policy_kwargs != entry.get("policy_kwargs")
    ):
        raise SettingsError(f"{FLAG} {path}: the config's policy_kwargs {entry.get('policy_kwargs')} are not the "
                            f"model's {record.policy_kwargs}: a trained network keeps its shape")  # fmt: skip
    stats = files.vecnormalize if files.vecnormalize.is_file() else None
    if bool(entry["normalize"]) != (stats is not None):
        have = f"its statistics are {stats}" if stats else f"there is no {files.vecnormalize.name} beside it"
        raise SettingsError(f"{FLAG} {path}: the config {'normalises' if entry['normalize'] else 'does not normalise'}"
                            f" observations and {have}: a policy keeps the observation scale it learned on")  # fmt: skip
    check_spaces(files.zip, env_id, entry)
    return files.zip, stats


def check_spaces(model_zip: Path, env_id: str, entry: dict[str, Any]) -> None:
    """The model's observation and action spaces against the env the config builds (one env, made and closed)."""
    from stable_baselines3.common.save_util import load_from_zip_file

    from ekfslam_gym.evaluation.rollout import make_env

    data, _, _ = load_from_zip_file(model_zip, load_data=True, device="cpu")
    env = make_env(env_id, entry["env_kwargs"])
    try:
        for name in ("observation_space", "action_space"):
            trained, here = data.get(name), getattr(env, name)
            if trained is not None and trained != here:
                raise SettingsError(f"{FLAG} {model_zip}: its {name.replace('_', ' ')} is {trained}, and {env_id} "
                                    f"with the config's env_kwargs has {here}")  # fmt: skip
    finally:
        env.close()
