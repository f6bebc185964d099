"""A training run: PPO (Stable-Baselines3) or RecurrentPPO (sb3-contrib) on an EKFSLAM env, from a validated
config entry (``settings``) into a run folder (``artefacts`` lists what it leaves there).

``train(env_id, seed, entry, out)`` is the entry for code (the sweep's Ray workers call it: a pip install has no
``train.py``); ``resume(out)`` continues a run; the command line is ``ekfslam_gym.cli.train``, which the
repository's ``train.py`` runs. Every setting is checked before the run folder is created. PPO collects whole
rollouts of ``n_steps * n_envs`` env steps, so a run trains ``n_timesteps`` rounded up to them, and says so.
With ``eval_freq`` the model is evaluated on the evaluation seeds every ``eval_freq`` env steps, and once at the
end when no evaluation fell inside the run, so ``best_model.zip`` and ``evaluations.npz`` always exist; with
``eval_freq`` 0 there is no evaluation, and the run says so.

With ``resume``, the run continues from its last checkpoint: weights, optimiser state, normalisation
statistics, timestep counter and random state; checkpoints are taken between rollouts, so the rollout that was
being collected when the run stopped is simply collected again.
"""

from __future__ import annotations

import os
import pickle
import random
import sys
from pathlib import Path
from typing import Any

from ekfslam_gym.agents.ppo import algo_class
from ekfslam_gym.artefacts import (
    BEST_MODEL,
    CHECKPOINTS,
    EVALUATIONS_FILE,
    MODEL,
    MONITOR,
    TENSORBOARD,
    ModelFiles,
    latest_checkpoint,
    read_run,
)

from .artefacts import plot_learning_curve, save_checkpoint, save_with_stats, write_record
from .settings import (
    NORMALIZE_DEFAULTS,
    TRAIN_KEYS,
    SettingsError,
    resolve_policy_kwargs,
    rollout_steps,
    schedule,
    steps_trained,
    validate_entry,
)
from .trained_agent import FLAG, check_trained_agent


# ---------------------------------------------------------------------------------------------- callbacks
def build_callbacks(out: Path, entry: dict[str, Any], eval_env, n_envs: int):
    """Checkpoints between rollouts (with normalisation and random state) and evaluation on fixed seeds."""
    from stable_baselines3.common.callbacks import BaseCallback, EvalCallback

    class RolloutCheckpoint(BaseCallback):
        """Save at the start of a rollout, when nothing is half-collected or half-trained."""

        def __init__(self, every: int) -> None:
            super().__init__()
            self.every = every
            self.next_at = None

        def _on_rollout_start(self) -> None:
            if self.next_at is None:
                self.next_at = (self.num_timesteps // self.every + 1) * self.every
                return
            if self.num_timesteps >= self.next_at:
                save_checkpoint(self.model, out, self.num_timesteps)
                self.next_at = (self.num_timesteps // self.every + 1) * self.every

        def _on_step(self) -> bool:
            return True

    class FixedSeedEval(EvalCallback):
        """EvalCallback on the same evaluation seeds every time, keeping the best model's statistics too, and
        continuing the evaluation history (and the best so far) of a resumed run."""

        def __init__(self, seed: int, **kwargs) -> None:
            super().__init__(**kwargs)
            self.eval_seed = seed
            previous = out / EVALUATIONS_FILE
            if previous.is_file():
                import numpy as np

                with np.load(previous) as data:
                    self.evaluations_timesteps = data["timesteps"].tolist()
                    self.evaluations_results = data["results"].tolist()
                    self.evaluations_length = data["ep_lengths"].tolist()
                if self.evaluations_results:
                    self.best_mean_reward = float(np.max(np.mean(self.evaluations_results, axis=1)))

        def evaluate_now(self) -> None:
            """One evaluation of the model as it stands, whatever ``eval_freq`` says (at the end of a run that
            none fell inside)."""
            every, self.eval_freq = self.eval_freq, 1
            try:
                self.on_step()
            finally:
                self.eval_freq = every

        def _on_step(self) -> bool:
            if self.eval_freq > 0 and self.n_calls % self.eval_freq == 0:
                self.eval_env.seed(self.eval_seed)
                best_before = self.best_mean_reward
                result = super()._on_step()
                if self.best_mean_reward > best_before:
                    save_with_stats(self.model, out / BEST_MODEL, out)
                return result
            return True

    callbacks = []
    if entry["checkpoint_freq"]:
        callbacks.append(RolloutCheckpoint(int(entry["checkpoint_freq"])))
    if entry["eval_freq"] and eval_env is not None:
        callbacks.append(
            FixedSeedEval(
                int(entry["eval_seed"]), eval_env=eval_env, n_eval_episodes=int(entry["eval_episodes"]),
                eval_freq=max(1, int(entry["eval_freq"]) // n_envs), log_path=str(out), deterministic=True,
                verbose=0,
            )
        )  # fmt: skip
    return callbacks


# ---------------------------------------------------------------------------------------------- envs
def make_envs(env_id: str, entry: dict[str, Any], n_envs: int, seed: int, monitor: Path, stats: Path | None):
    """Training and evaluation vector envs, normalised as the entry says (eval: statistics frozen)."""
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecNormalize

    import ekfslam_gym  # noqa: F401  (registers the envs in this process)

    qualified = env_id if ":" in env_id else f"ekfslam_gym:{env_id}"
    vec_cls = SubprocVecEnv if entry["vec_env"] == "subproc" and n_envs > 1 else DummyVecEnv
    env_kwargs = dict(entry["env_kwargs"])
    train_env = make_vec_env(qualified, n_envs=n_envs, seed=seed, vec_env_cls=vec_cls, env_kwargs=env_kwargs,
                             monitor_dir=str(monitor))  # fmt: skip
    eval_env = make_vec_env(qualified, n_envs=1, seed=int(entry["eval_seed"]), env_kwargs=env_kwargs)
    normalize = entry["normalize"]
    if normalize:
        kwargs = {**NORMALIZE_DEFAULTS, **(normalize if isinstance(normalize, dict) else {})}
        if "gamma" in entry:
            kwargs.setdefault("gamma", entry["gamma"])
        if stats is not None:
            train_env = VecNormalize.load(str(stats), train_env)
            train_env.training = True
        else:
            train_env = VecNormalize(train_env, **kwargs)
        eval_env = VecNormalize(eval_env, training=False, norm_obs=kwargs["norm_obs"], norm_reward=False,
                                norm_obs_keys=kwargs.get("norm_obs_keys"))  # fmt: skip
    return train_env, eval_env


# ---------------------------------------------------------------------------------------------- runs
def train(
    env_id: str,
    seed: int,
    entry: dict[str, Any],
    out: Path,
    *,
    resume: bool = False,
    progress: bool = True,
    command: list[str] | None = None,
    trained_agent: str | Path | None = None,
) -> Path:
    """Train ``entry["algo"]`` (PPO by default) on ``env_id`` with the resolved config ``entry`` into the run
    folder ``out``; returns ``out``.

    With ``resume``, continue the run in ``out`` from its last checkpoint up to ``entry["n_timesteps"]`` (see
    the module docstring); ``command`` is the command line recorded in ``config.yaml`` (the arguments of
    ``python train.py ...`` that repeat the run). With ``trained_agent`` (a saved model, or an env id's shipped
    policy), a new run starts from its weights, optimiser state and normalisation statistics
    (``trained_agent.check_trained_agent``). Raises ``SettingsError`` (a ``ValueError``) for a setting that
    cannot train (``settings.validate_entry``) or a resume with no checkpoint, before anything is created.
    """
    out = Path(out)
    entry = validate_entry(entry, env_id, seed)
    if trained_agent is not None and resume:
        raise SettingsError(f"{FLAG} starts a new run and --resume continues one from its own checkpoints: "
                            "give one of them")  # fmt: skip
    checkpoint = latest_checkpoint(out / CHECKPOINTS) if resume else None
    if resume and checkpoint is None:
        raise SettingsError(f"{out / CHECKPOINTS} holds no checkpoint to resume from")
    trained_zip, trained_stats = (
        (None, None) if trained_agent is None else check_trained_agent(trained_agent, env_id, entry)
    )

    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    import numpy as np
    import torch

    algo = algo_class(entry["algo"])
    torch.set_num_threads(int(entry["torch_threads"]))
    n_envs = int(entry["n_envs"])
    total = int(entry["n_timesteps"])
    write_record(out, env_id, seed, entry, command)

    stats = trained_stats
    if checkpoint is not None:
        stats_path = ModelFiles.of(checkpoint[0]).vecnormalize
        stats = stats_path if stats_path.is_file() else None
    # Resumed runs reseed their envs from the step count, so a resumed run is itself reproducible.
    env_seed = seed if checkpoint is None else seed + checkpoint[1]
    # Each run segment logs its episodes to a folder of its own, so resuming never overwrites a monitor file.
    monitor = out / MONITOR / f"from_{0 if checkpoint is None else checkpoint[1]}"
    train_env, eval_env = make_envs(env_id, entry, n_envs, env_seed, monitor, stats)

    hyper = {k: schedule(v) if k in ("learning_rate", "clip_range") else v
             for k, v in entry.items() if k not in TRAIN_KEYS}  # fmt: skip
    if "policy_kwargs" in hyper:
        hyper["policy_kwargs"] = resolve_policy_kwargs(hyper["policy_kwargs"])
    if checkpoint is None and trained_agent is not None:
        hyper.pop("policy_kwargs", None)  # the network is the trained model's own
        model = algo.load(str(trained_zip), env=train_env, seed=seed,
                          tensorboard_log=str(out / TENSORBOARD), verbose=0, **hyper)  # fmt: skip
        print(f"starting from the trained agent {trained_zip}", file=sys.stderr)
        remaining = total
        reset = True
    elif checkpoint is None:
        model = algo(
            entry["policy"], train_env, seed=seed, tensorboard_log=str(out / TENSORBOARD), verbose=0, **hyper
        )
        if entry["pretrain"] is not None:  # planner-guided: behaviour cloning before PPO
            from .pretraining import pretrain

            report = pretrain(model, env_id, entry, out)["clone"]
            kept = "" if report["kept_epoch"] == report["epochs"] else f" (epoch {report['kept_epoch']} kept)"
            print(f"behaviour cloning: accuracy {report['train_accuracy']:.3f} on the demonstrations, "
                  f"{report['holdout_accuracy']:.3f} on the held-back ones{kept}", file=sys.stderr)  # fmt: skip
        remaining = total
        reset = True
    else:
        path, done = checkpoint
        model = algo.load(str(path), env=train_env, tensorboard_log=str(out / TENSORBOARD))
        with open(ModelFiles.of(path).rng, "rb") as handle:
            state = pickle.load(handle)
        random.setstate(state["python"])
        np.random.set_state(state["numpy"])  # noqa: NPY002
        torch.set_rng_state(state["torch"])
        remaining = total - done
        reset = False
        print(f"resuming {out} from {done} steps ({remaining} to go)", file=sys.stderr)

    callbacks = build_callbacks(out, entry, eval_env, n_envs)
    if entry["pretrain"] is not None and entry["pretrain"]["keep_cloning"]:
        from .keep_cloning import keep_cloning_callback  # imports torch and SB3

        callbacks.append(keep_cloning_callback(model, out, entry["pretrain"]))
    done = total - remaining
    if steps_trained(entry, done) != max(total, done):
        print(f"note: {entry['algo']} collects whole rollouts of n_steps x n_envs = {rollout_steps(entry)} env "
              f"steps, so this run trains to {steps_trained(entry, done)} steps, not {total}", file=sys.stderr)  # fmt: skip
    if remaining > 0:
        # A bar redraws itself with carriage returns: only on a terminal, never into a log or a pipe.
        bar = progress and getattr(sys.stdout, "isatty", lambda: False)()
        model.learn(total_timesteps=remaining, callback=callbacks, progress_bar=bar,
                    reset_num_timesteps=reset, tb_log_name=entry["algo"])  # fmt: skip
        evaluate_at_the_end(callbacks, entry, model.num_timesteps)
    save_with_stats(model, out / MODEL, out)
    save_checkpoint(model, out, model.num_timesteps)
    train_env.close()
    eval_env.close()
    plot_learning_curve(out)
    print(f"trained {model.num_timesteps} steps; model in {ModelFiles(out / MODEL).zip}", file=sys.stderr)
    return out


def evaluate_at_the_end(callbacks: list[Any], entry: dict[str, Any], steps: int) -> None:
    """Evaluate once more when no evaluation fell inside the run (``eval_freq`` beyond its length), so
    ``best_model.zip`` and ``evaluations.npz`` exist; with ``eval_freq`` 0 say that there are none."""
    evaluation = next((c for c in callbacks if hasattr(c, "evaluate_now")), None)
    if evaluation is None:
        print("no evaluation (eval_freq is 0): no best_model.zip and no evaluations.npz", file=sys.stderr)
    elif not evaluation.evaluations_timesteps:
        print(f"no evaluation fell inside the run (eval_freq {entry['eval_freq']}, {steps} steps): evaluating "
              "the final model once", file=sys.stderr)  # fmt: skip
        evaluation.evaluate_now()


def resume(out: Path, timesteps: int | None = None, *, progress: bool = True) -> Path:
    """Continue the run in ``out`` from its last checkpoint up to ``timesteps`` (default: the run's own
    ``n_timesteps``), as ``train.py --resume OUT [--timesteps N]`` does; returns ``out``."""
    env_id, seed, entry = read_run(out)
    if timesteps is not None:
        entry["n_timesteps"] = int(timesteps)
    command = ["--resume", str(out), *(["--timesteps", str(timesteps)] if timesteps is not None else [])]
    return train(env_id, seed, entry, out, resume=True, progress=progress,
                 command=command + ([] if progress else ["--no-progress"]))  # fmt: skip
