"""Training sweeps on Ray Core: one task per (env id, training seed) that trains with ``ekfslam_gym.training.run``
and evaluates the final policy on evaluation seeds, each task declaring the one CPU it uses.

A trial's folder ``<out>/<env-id>_seed<S>/`` holds ``train.py``'s usual outputs plus ``result.json`` (the
per-episode metrics of ``ekfslam_gym.evaluation.episode_metrics``). A trial with ``result.json`` is finished and
is not run again; one with checkpoints but no result resumes (``run.resume``, as ``train.py --resume``); anything
else starts over.

The final model (``model.zip``) is evaluated, not ``best_model.zip``: the best model is chosen on the evaluation
seeds, so scoring it on them again would flatter it. Evaluation seeds must lie outside the held-out suite
(``ekfslam_gym.seeds``: it is for the final table only). Ray is imported only when a sweep runs (the
``cluster`` extra); on a cluster every node needs this package installed with the ``train`` extra.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ekfslam_gym.agents.ppo import PPOAgent
from ekfslam_gym.artefacts import CHECKPOINTS, MODEL, RECORD_FILE, ModelFiles, latest_checkpoint, read_run
from ekfslam_gym.evaluation.report import json_safe
from ekfslam_gym.evaluation.rollout import evaluate_agent
from ekfslam_gym.seeds import SELECTION_SEEDS, check_not_held_out

from .run import resume, train

RESULT_FILE = "result.json"
# One thread per library in every task: Ray counts a task as one CPU, and a BLAS or torch pool per task would
# oversubscribe the node's cores.
SINGLE_THREAD_ENV = {"OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}


@dataclass(frozen=True)
class Trial:
    """One training run of a sweep and its evaluation: what a Ray task receives."""

    env_id: str
    seed: int
    entry: dict[str, Any] = field(hash=False, compare=False)
    out: Path
    eval_seeds: tuple[int, ...] = SELECTION_SEEDS
    command: tuple[str, ...] = ()

    @property
    def name(self) -> str:
        return f"{self.env_id}_seed{self.seed}"

    @property
    def folder(self) -> Path:
        return self.out / self.name


def trial_state(folder: Path) -> str:
    """``"done"`` (``result.json`` exists), ``"resume"`` (checkpoints, no result) or ``"new"``."""
    if (folder / RESULT_FILE).is_file():
        return "done"
    if latest_checkpoint(folder / CHECKPOINTS) is not None:
        return "resume"
    return "new"


def run_trial(trial: Trial) -> dict[str, Any]:
    """Train (or resume, or skip) the trial, evaluate its final model and write ``result.json``; returns it.

    ``result.json``: ``env_id``, ``seed``, ``timesteps`` (steps the model was trained), ``trained_steps`` (steps
    trained by this call, 0 for a finished trial), ``train_seconds``, ``eval_seconds``, ``eval_seeds`` and
    ``episodes`` (one metrics dict per evaluation seed, NaN written as null).
    """
    folder = trial.folder
    state = trial_state(folder)
    if state == "done":
        return {**json.loads((folder / RESULT_FILE).read_text()), "trained_steps": 0, "state": state}
    check_not_held_out(trial.eval_seeds, "evaluation seeds")

    import torch

    torch.set_num_threads(1)
    started = time.perf_counter()
    if state == "resume":
        before = latest_checkpoint(folder / CHECKPOINTS)[1]
        resume(folder, int(trial.entry["n_timesteps"]), progress=False)
    else:
        before = 0
        if (folder / RECORD_FILE).is_file():  # an interrupted run with no checkpoint: its logs are stale
            shutil.rmtree(folder)
        train(trial.env_id, trial.seed, dict(trial.entry), folder, progress=False,
                       command=list(trial.command))  # fmt: skip
    train_seconds = time.perf_counter() - started
    timesteps = latest_checkpoint(folder / CHECKPOINTS)[1]

    env_id, _, entry = read_run(folder)
    started = time.perf_counter()
    # make_env hands a max_episode_steps among the training env_kwargs to gym.make as its own argument
    episodes = evaluate_agent(PPOAgent(ModelFiles(folder / MODEL).zip), env_id, trial.eval_seeds, entry["env_kwargs"],
                              label=trial.name)  # fmt: skip
    result = {
        "env_id": env_id,
        "seed": trial.seed,
        "timesteps": timesteps,
        "train_seconds": train_seconds,
        "eval_seconds": time.perf_counter() - started,
        "eval_seeds": list(trial.eval_seeds),
        "episodes": json_safe(episodes),
    }
    (folder / RESULT_FILE).write_text(json.dumps(result, indent=1, allow_nan=False))
    return {**result, "trained_steps": timesteps - before, "state": state}


def run_trials(
    trials: Sequence[Trial],
    *,
    address: str | None = None,
    workers: int | None = None,
    log: Callable[[str], None] = lambda line: print(line, file=sys.stderr, flush=True),
) -> tuple[list[dict[str, Any]], list[tuple[Trial, str]]]:
    """Run the trials as Ray tasks, finished ones read back without starting Ray; returns (results in the
    order of ``trials``, (trial, error) of the trials that failed).

    ``address`` None starts an embedded local Ray with ``workers`` CPUs (default: the machine's cores);
    ``"auto"`` or ``"ray://host:port"`` joins a running cluster (``ray start --head`` and ``ray start
    --address HEAD:6379``), whose size sets the parallelism.
    """
    results: dict[int, dict[str, Any]] = {}
    failures: list[tuple[Trial, str]] = []
    pending = []
    for index, trial in enumerate(trials):
        if trial_state(trial.folder) == "done":
            results[index] = run_trial(trial)
            log(f"skip {trial.name}: {trial.folder / RESULT_FILE} exists")
        else:
            pending.append(index)
    if pending:
        import ray

        if address is None:
            ray.init(num_cpus=workers or os.cpu_count() or 1, include_dashboard=False,
                     object_store_memory=100 * 1024**2, configure_logging=False)  # fmt: skip
        else:
            ray.init(address=address, configure_logging=False)
        try:
            task = ray.remote(num_cpus=1, runtime_env={"env_vars": SINGLE_THREAD_ENV})(run_trial)
            running = {task.remote(trials[i]): i for i in pending}
            for i in pending:
                log(f"queued {trials[i].name} ({trial_state(trials[i].folder)})")
            while running:
                (ref,), _ = ray.wait(list(running), num_returns=1)
                index = running.pop(ref)
                name = trials[index].name
                try:
                    results[index] = result = ray.get(ref)
                except Exception as error:  # a failed trial does not stop the others
                    failures.append((trials[index], str(error)))
                    log(f"FAILED {name}: {str(error).strip().splitlines()[-1]}")
                    continue
                log(f"done {name}: {result['timesteps']} steps in {result['train_seconds']:.1f} s, "
                    f"evaluated on {len(result['episodes'])} seeds ({len(results)}/{len(trials)})")  # fmt: skip
        finally:
            ray.shutdown()
    return [results[i] for i in sorted(results)], failures
