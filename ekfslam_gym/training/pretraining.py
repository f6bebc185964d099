"""Planner-guided training's warm start: the run's demonstrations, the normalisation statistics fitted to them,
behaviour cloning, and DAgger rounds, before PPO's first update.

``pretrain(model, env_id, entry, out)`` is what ``ekfslam_gym.training.run`` runs before ``learn()`` when the
config's ``train_settings`` hold a ``pretrain`` section (``settings.PRETRAIN_DEFAULTS`` lists its keys, checked
once by ``settings.validate_entry``); a resumed run never clones again.
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from ekfslam_gym.agents.ppo import PPOAgent
from ekfslam_gym.artefacts import BC_MODEL, DAGGER_FILE, DEMONSTRATIONS_FILE, PRETRAIN_FILE

from .artefacts import save_with_stats
from .cloning import CloneReport, behaviour_clone, fit_normalizer, split_episodes
from .demonstrations import Demonstrations, collect, concatenate, env_reward_weights, load, reweighted, save
from .settings import SettingsError, demonstration_seeds, run_selection_seeds


def demonstrations_for(
    env_id: str, entry: Mapping[str, Any], settings: Mapping[str, Any], out: Path
) -> Demonstrations:
    """The run's demonstrations: ``settings["path"]`` if given, else collected and saved in ``out`` as
    ``demonstrations.npz``. A file must be of the run's env id and env_kwargs; only the ``reward`` may differ,
    and then its rewards are recomputed under the run's weights (``reweighted``), since the weights change the
    reward and never the trajectory."""
    env_kwargs = dict(entry.get("env_kwargs") or {})
    if settings.get("path"):
        demos = load(settings["path"])
        recorded = (demos.meta.get("env_id"), demos.meta.get("env_kwargs"))
        if recorded == (env_id, env_kwargs):
            return demos
        if recorded[0] != env_id or _without_reward(recorded[1] or {}) != _without_reward(env_kwargs):
            raise SettingsError(
                f"pretrain.path: {settings['path']} holds demonstrations of {recorded[0]} with env_kwargs {recorded[1]}, "
                f"this run trains {env_id} with {env_kwargs}"
            )
        try:
            demos = reweighted(demos, env_reward_weights(env_id, env_kwargs))
        except ValueError as error:
            raise SettingsError(f"pretrain.path: {settings['path']}: {error}") from None
        demos.meta.update(env_kwargs=env_kwargs, reweighted_from=str(settings["path"]))
        return demos
    demos = collect(env_id, demonstration_seeds(settings), env_kwargs, planner=settings["planner"],
                    planner_kwargs=settings["planner_kwargs"], eval_seeds=run_selection_seeds(entry))  # fmt: skip
    save(demos, Path(out) / DEMONSTRATIONS_FILE)
    return demos


def _without_reward(env_kwargs: Mapping[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in env_kwargs.items() if k != "reward"}


def pretrain(model: Any, env_id: str, entry: Mapping[str, Any], out: Path) -> dict[str, Any] | None:
    """The ``pretrain`` step of a training run whose ``entry`` is validated (``settings.validate_entry``; no-op
    without the setting): demonstrations, normalisation
    statistics fitted to them, behaviour cloning, then ``dagger_rounds`` DAgger rounds (the clone drives
    ``dagger_episodes`` episodes, the planner labels the observations it reaches, the clone is trained again on
    everything; Ross, Gordon & Bagnell 2011). Writes ``pretrain.json`` (settings, one ``CloneReport`` per
    round, and per DAgger round the fraction of the clone's own decisions that matched the planner's) and the
    cloned policy as ``bc_model.zip`` (with its statistics and the run's config) in ``out``; with DAgger, the
    aggregated pairs as ``dagger.npz``."""
    settings = entry.get("pretrain")
    if settings is None:
        return None
    out = Path(out)
    start = time.perf_counter()
    demos = demonstrations_for(env_id, entry, settings, out)
    collected = time.perf_counter() - start
    reused = set(demos.seeds.tolist()) & set(demonstration_seeds(settings, -1)[settings["episodes"] :])
    if reused:
        raise SettingsError(
            f"pretrain.seed: DAgger seeds {sorted(reused)[:5]} are among the demonstrations' own; move pretrain.seed"
        )
    rng = np.random.default_rng(settings["seed"])
    held = np.isin(
        demos.episodes, demos.episodes[split_episodes(demos.episodes, settings["holdout"], rng)[1]]
    )
    normalizer = model.get_vec_normalize_env()

    def clone(epochs: int) -> CloneReport:
        if normalizer is not None:
            fit_normalizer(normalizer, demos)
        return behaviour_clone(model, demos, epochs=epochs, batch_size=settings["batch_size"],
                               learning_rate=settings["learning_rate"], value=settings["value"],
                               seed=settings["seed"], held=held, best_epoch=settings["best_epoch"])  # fmt: skip

    reports = [clone(settings["epochs"])]
    agreement = []
    for round_ in range(settings["dagger_rounds"]):
        tick = time.perf_counter()
        more = collect(env_id, demonstration_seeds(settings, round_), dict(entry.get("env_kwargs") or {}),
                       planner=settings["planner"], planner_kwargs=settings["planner_kwargs"],
                       driver=PPOAgent(model=model, vecnormalize=normalizer),
                       eval_seeds=run_selection_seeds(entry))  # fmt: skip
        collected += time.perf_counter() - tick
        # The clone drove deterministically, so its accuracy on what it reached is its agreement with the planner.
        on_policy = behaviour_clone(model, more, epochs=0, held=np.ones(len(more), dtype=bool))
        agreement.append(on_policy.holdout_accuracy)
        split = split_episodes(more.episodes, settings["holdout"], rng)[1]
        held = np.concatenate([held, np.isin(more.episodes, more.episodes[split])])
        demos = concatenate(demos, more)
        reports.append(clone(settings["epochs"]))
    if settings["dagger_rounds"]:
        save(demos, out / DAGGER_FILE)
    save_with_stats(model, out / BC_MODEL, out)
    record = {"settings": dict(settings), "pairs": len(demos), "episodes": int(len(demos.seeds)),
              "demonstration_seconds": collected, "clone": asdict(reports[-1]),
              "rounds": [asdict(r) for r in reports], "dagger_agreement": agreement}  # fmt: skip
    (out / PRETRAIN_FILE).write_text(json.dumps(record, indent=2))
    return record
