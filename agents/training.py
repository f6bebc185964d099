"""Train PPO (Stable-Baselines3) or RecurrentPPO (sb3-contrib) on an EKFSLAM env from a YAML config in rl-zoo3 style.

``train(env_id, seed, entry, out)`` is the entry for code (the sweep's Ray workers import it: a pip install has
no ``train.py``); ``main`` is the command line, which the repository's ``train.py`` runs:

    python train.py --config configs/ppo.yaml [--env-id ID] [--timesteps N] [--seed S] [--n-envs K]
                    [--out DIR] [--resume DIR] [--hyperparams KEY=VALUE ...] [--no-progress]

The config is rl-zoo3's own format, so ``python -m rl_zoo3.train -conf`` reads the same file: one entry per env
id with the PPO hyperparameters plus ``n_timesteps``, ``n_envs``, ``normalize`` (VecNormalize: false, true, or
its keyword arguments) and ``env_kwargs``. The settings only this script knows sit in a top-level
``train_settings`` section, keyed by env id, where rl-zoo3 does not look: ``vec_env`` (dummy | subproc),
``eval_freq``/``eval_episodes``/``eval_seed`` (model selection on evaluation seeds, never the held-out suite),
``checkpoint_freq`` (total env steps), ``torch_threads``, ``algo`` (rl-zoo3's name of the algorithm: ``ppo``, the
default, or ``ppo_lstm``, sb3-contrib's RecurrentPPO with ``policy: MlpLstmPolicy`` or ``MultiInputLstmPolicy``;
``ekfslam_gym.agents.ppo.ALGOS``; rl-zoo3 takes it as ``--algo``) and ``pretrain`` (planner-guided training: a planner's
demonstrations, greedy's or frontier's, cloned into the policy before PPO, ``ekfslam_gym.agents.imitation``; absent means
none, and a resumed run never clones again; either algo; its ``keep_cloning`` keeps cloning steps up between
PPO's updates, resumed runs included, ``ekfslam_gym.agents.keep_cloning``). ``--hyperparams`` overrides either kind. Class names in
``policy_kwargs`` (``features_extractor_class``, ``activation_fn``, ``optimizer_class``) may be given dotted,
e.g. ``ekfslam_gym.agents.extractors.BeliefCNN`` or ``torch.nn.ReLU`` (``nn.ReLU`` too): they are imported when the model
is built, and the record keeps the names. The output folder receives:

- ``model.zip`` + ``model_vecnormalize.pkl``: the final policy and its normalisation statistics;
- ``best_model.zip`` + ``best_model_vecnormalize.pkl``: the best on the evaluation seeds;
- ``checkpoints/``: ``ppo_<steps>_steps.zip`` with ``..._vecnormalize.pkl`` and ``..._rng.pkl`` (random state);
- ``config.yaml`` (the resolved entry and command line) and ``versions.json``, copied beside every model as
  ``<model>_config.yaml`` and ``<model>_versions.json``;
- ``tb/`` tensorboard logs, ``monitor/`` episode logs, ``evaluations.npz`` and ``learning_curve.png``;
- with ``pretrain``: ``bc_model.zip`` (+ statistics, config, versions), the cloned policy before any PPO update;
  ``demonstrations.npz`` (``dagger.npz`` with DAgger rounds) and ``pretrain.json`` (settings, accuracies).

``--resume DIR`` continues the run in DIR from its last checkpoint: weights, optimiser state, normalisation
statistics, timestep counter and random state; checkpoints are taken between rollouts, so the rollout that was
being collected when the run stopped is simply collected again.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import platform
import random
import re
import sys
from importlib import metadata
from pathlib import Path
from typing import Any

import yaml

from ekfslam_gym.seeds import EVAL_SEED_START, SELECTION_EPISODES

from .imitation import validate_pretrain
from .ppo import ALGOS, algo_class

NORMALIZE_DEFAULTS = {"norm_obs": True, "norm_reward": True}
TRAIN_KEYS = {
    "n_timesteps", "policy", "n_envs", "vec_env", "normalize", "env_kwargs", "eval_freq", "eval_episodes",
    "eval_seed", "checkpoint_freq", "torch_threads", "pretrain", "algo",
}  # fmt: skip
SETTINGS_SECTION = "train_settings"
SETTINGS_KEYS = {
    "vec_env", "eval_freq", "eval_episodes", "eval_seed", "checkpoint_freq", "torch_threads", "pretrain", "algo",
}  # fmt: skip
# policy_kwargs entries that name a class or function, resolved from a dotted name (``resolve_policy_kwargs``).
CLASS_KWARGS = ("features_extractor_class", "activation_fn", "optimizer_class")


# ---------------------------------------------------------------------------------------------- config
def load_entry(config_path: Path, env_id: str) -> dict[str, Any]:
    """The config entry for ``env_id``, with every training key defaulted and checked."""
    data = yaml.safe_load(Path(config_path).read_text()) or {}
    settings = data.pop(SETTINGS_SECTION, None) or {}
    if env_id not in data:
        raise SystemExit(f"{config_path} has no entry for {env_id!r}; it has {sorted(data)}")
    entry = dict(data[env_id])
    misplaced = sorted(SETTINGS_KEYS & set(entry))
    if misplaced:
        raise SystemExit(
            f"{config_path}: {misplaced} in the {env_id!r} entry would reach PPO under rl-zoo3; "
            f"put them under '{SETTINGS_SECTION}: {{{env_id}: ...}}'"
        )
    extra = dict(settings.get(env_id) or {})
    unknown = sorted(set(extra) - SETTINGS_KEYS)
    if unknown:
        raise SystemExit(
            f"{config_path}: unknown {SETTINGS_SECTION} keys {unknown} for {env_id!r}; "
            f"known: {sorted(SETTINGS_KEYS)}"
        )
    entry.update(extra)
    entry.setdefault("n_timesteps", 100_000)
    entry.setdefault("policy", "MlpPolicy")
    entry.setdefault("n_envs", 1)
    entry.setdefault("vec_env", "dummy")
    entry.setdefault("normalize", False)
    entry.setdefault("env_kwargs", {})
    entry.setdefault("eval_freq", 0)
    entry.setdefault("eval_episodes", SELECTION_EPISODES)
    entry.setdefault("eval_seed", EVAL_SEED_START)
    entry.setdefault("checkpoint_freq", 0)
    entry.setdefault("torch_threads", 1)
    entry.setdefault("pretrain", None)
    entry.setdefault("algo", "ppo")
    if entry["vec_env"] not in ("dummy", "subproc"):
        raise SystemExit(f"vec_env must be dummy or subproc, got {entry['vec_env']!r}")
    try:
        check_algo(entry)
        entry["pretrain"] = validate_pretrain(entry["pretrain"], entry)
    except ValueError as error:
        raise SystemExit(f"{config_path}: {SETTINGS_SECTION} for {env_id!r}: {error}") from None
    return entry


def check_algo(entry: dict[str, Any]) -> None:
    """ValueError for an unknown ``algo``."""
    algo = entry.get("algo", "ppo")
    if algo not in ALGOS:
        raise ValueError(f"algo must be one of {sorted(ALGOS)}, got {algo!r}")


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
    """``policy_kwargs`` with the class names of ``CLASS_KWARGS`` given as dotted strings imported."""
    if kwargs is None:
        return None
    return {k: import_dotted(v) if k in CLASS_KWARGS and isinstance(v, str) else v for k, v in kwargs.items()}


def parse_hyperparams(pairs: list[str]) -> dict[str, Any]:
    """KEY=VALUE pairs, each VALUE parsed as YAML (so 3e-4, true, [64, 64] and {a: 1} work)."""
    out = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise SystemExit(f"--hyperparams takes KEY=VALUE pairs, got {pair!r}")
        out[key] = yaml.safe_load(value)
    return out


def schedule(value: Any) -> Any:
    """rl-zoo3's ``lin_X``: a learning rate falling linearly from X to 0 over the run; numbers pass through."""
    if isinstance(value, str) and value.startswith("lin_"):
        start = float(value[4:])
        return lambda progress_remaining: progress_remaining * start
    return value


def versions() -> dict[str, str]:
    found = {"python": platform.python_version()}
    for name in (
        "ekfslam-gym",
        "numpy",
        "scipy",
        "numba",
        "pymunk",
        "gymnasium",
        "stable-baselines3",
        "sb3-contrib",
        "torch",
    ):
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "not installed"
    return found


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
            previous = out / "evaluations.npz"
            if previous.is_file():
                import numpy as np

                with np.load(previous) as data:
                    self.evaluations_timesteps = data["timesteps"].tolist()
                    self.evaluations_results = data["results"].tolist()
                    self.evaluations_length = data["ep_lengths"].tolist()
                if self.evaluations_results:
                    self.best_mean_reward = float(np.max(np.mean(self.evaluations_results, axis=1)))

        def _on_step(self) -> bool:
            if self.eval_freq > 0 and self.n_calls % self.eval_freq == 0:
                self.eval_env.seed(self.eval_seed)
                best_before = self.best_mean_reward
                result = super()._on_step()
                if self.best_mean_reward > best_before:
                    save_with_stats(self.model, out / "best_model", out)
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


def save_with_stats(model, stem: Path, run: Path) -> None:
    """``stem.zip``, ``stem_vecnormalize.pkl`` if the model normalises (the convention the agents load), and the
    run's config and package versions beside it as ``stem_config.yaml`` and ``stem_versions.json``."""
    stem.parent.mkdir(parents=True, exist_ok=True)
    model.save(str(stem) + ".zip")
    normalizer = model.get_vec_normalize_env()
    if normalizer is not None:
        normalizer.save(str(stem) + "_vecnormalize.pkl")
    for name, suffix in (("config.yaml", "_config.yaml"), ("versions.json", "_versions.json")):
        (Path(str(stem) + suffix)).write_text((run / name).read_text())


def save_checkpoint(model, run: Path, steps: int) -> None:
    import numpy as np
    import torch

    stem = run / "checkpoints" / f"ppo_{steps}_steps"
    save_with_stats(model, stem, run)
    # SB3 draws from the legacy global numpy RNG, so that is the state to keep.
    state = {"python": random.getstate(), "numpy": np.random.get_state(), "torch": torch.get_rng_state()}  # noqa: NPY002
    with open(str(stem) + "_rng.pkl", "wb") as handle:
        pickle.dump(state, handle)


def latest_checkpoint(folder: Path) -> tuple[Path, int] | None:
    found = []
    for path in folder.glob("ppo_*_steps.zip"):
        match = re.fullmatch(r"ppo_(\d+)_steps\.zip", path.name)
        if match:
            found.append((int(match.group(1)), path))
    if not found:
        return None
    steps, path = max(found)
    return path, steps


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
def resolve_entry(
    config: Path,
    env_id: str,
    hyperparams: dict[str, Any] | None = None,
    *,
    timesteps: int | None = None,
    n_envs: int | None = None,
) -> dict[str, Any]:
    """The entry a run trains with: the config's entry for ``env_id``, then ``hyperparams``, then the
    ``timesteps`` and ``n_envs`` overrides (the order of the command line's options)."""
    entry = load_entry(config, env_id)
    entry.update(hyperparams or {})
    if timesteps is not None:
        entry["n_timesteps"] = timesteps
    if n_envs is not None:
        entry["n_envs"] = n_envs
    return entry


def read_run(folder: Path) -> tuple[str, int, dict[str, Any]]:
    """(env id, seed, entry) recorded in a run folder's ``config.yaml``, what ``--resume`` continues."""
    path = Path(folder) / "config.yaml"
    if not path.is_file():
        raise FileNotFoundError(f"{folder} is not a training run folder (no config.yaml)")
    saved = yaml.safe_load(path.read_text())
    return saved["env_id"], int(saved["seed"]), dict(saved["entry"])


def train(
    env_id: str,
    seed: int,
    entry: dict[str, Any],
    out: Path,
    *,
    resume: bool = False,
    progress: bool = True,
    command: list[str] | None = None,
) -> Path:
    """Train ``entry["algo"]`` (PPO by default) on ``env_id`` with the resolved config ``entry`` into the run
    folder ``out``; returns ``out``.

    With ``resume``, continue the run in ``out`` from its last checkpoint up to ``entry["n_timesteps"]`` (see
    the module docstring); ``command`` is the command line recorded in ``config.yaml`` (the arguments of
    ``python train.py ...`` that repeat the run). Raises ``ValueError`` for a non-positive step count or a
    resume with no checkpoint.
    """
    out = Path(out)
    if int(entry["n_timesteps"]) <= 0:
        raise ValueError("--timesteps must be positive")
    checkpoint = latest_checkpoint(out / "checkpoints") if resume else None
    if resume and checkpoint is None:
        raise ValueError(f"{out / 'checkpoints'} holds no checkpoint to resume from")
    entry = {"algo": "ppo", **entry}
    entry["pretrain"] = validate_pretrain(entry.get("pretrain"), entry)  # after --hyperparams
    check_algo(entry)

    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    import numpy as np
    import torch

    algo = algo_class(entry["algo"])
    torch.set_num_threads(int(entry["torch_threads"]))
    out.mkdir(parents=True, exist_ok=True)
    n_envs = int(entry["n_envs"])
    total = int(entry["n_timesteps"])
    record = {"env_id": env_id, "seed": seed, "entry": entry, "argv": list(command or [])}
    (out / "config.yaml").write_text(yaml.safe_dump(record, sort_keys=False))
    (out / "versions.json").write_text(json.dumps(versions(), indent=2))

    stats = None
    if checkpoint is not None:
        stats_path = Path(str(checkpoint[0])[: -len(".zip")] + "_vecnormalize.pkl")
        stats = stats_path if stats_path.is_file() else None
    # Resumed runs reseed their envs from the step count, so a resumed run is itself reproducible.
    env_seed = seed if checkpoint is None else seed + checkpoint[1]
    # Each run segment logs its episodes to a folder of its own, so resuming never overwrites a monitor file.
    monitor = out / "monitor" / f"from_{0 if checkpoint is None else checkpoint[1]}"
    train_env, eval_env = make_envs(env_id, entry, n_envs, env_seed, monitor, stats)

    hyper = {k: schedule(v) if k in ("learning_rate", "clip_range") else v
             for k, v in entry.items() if k not in TRAIN_KEYS}  # fmt: skip
    if "policy_kwargs" in hyper:
        hyper["policy_kwargs"] = resolve_policy_kwargs(hyper["policy_kwargs"])
    if checkpoint is None:
        model = algo(
            entry["policy"], train_env, seed=seed, tensorboard_log=str(out / "tb"), verbose=0, **hyper
        )
        if (
            entry["pretrain"] is not None
        ):  # planner-guided: behaviour cloning before PPO (ekfslam_gym.agents.imitation)
            from .imitation import pretrain

            report = pretrain(model, env_id, entry, out)["clone"]
            kept = "" if report["kept_epoch"] == report["epochs"] else f" (epoch {report['kept_epoch']} kept)"
            print(f"behaviour cloning: accuracy {report['train_accuracy']:.3f} on the demonstrations, "
                  f"{report['holdout_accuracy']:.3f} on the held-back ones{kept}", file=sys.stderr)  # fmt: skip
        remaining = total
        reset = True
    else:
        path, done = checkpoint
        model = algo.load(str(path), env=train_env, tensorboard_log=str(out / "tb"))
        with open(str(path)[: -len(".zip")] + "_rng.pkl", "rb") as handle:
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
    if remaining > 0:
        # A bar redraws itself with carriage returns: only on a terminal, never into a log or a pipe.
        bar = progress and getattr(sys.stdout, "isatty", lambda: False)()
        model.learn(total_timesteps=remaining, callback=callbacks, progress_bar=bar,
                    reset_num_timesteps=reset, tb_log_name=entry["algo"])  # fmt: skip
    save_with_stats(model, out / "model", out)
    save_checkpoint(model, out, model.num_timesteps)
    train_env.close()
    eval_env.close()
    plot_learning_curve(out)
    print(f"trained {model.num_timesteps} steps; model in {out / 'model.zip'}", file=sys.stderr)
    return out


def read_monitor(folder: Path):
    """(return, length, wall time) of every finished training episode in SB3's monitor CSVs (no pandas)."""
    import numpy as np

    rows = []
    for path in sorted(folder.rglob("*.monitor.csv")):
        lines = (
            path.read_text().splitlines()
        )  # '#{json header with t_start}', 'r,l,t', then one row an episode
        if len(lines) < 3:
            continue
        t_start = json.loads(lines[0].lstrip("#"))["t_start"]
        for line in lines[2:]:
            r, length, t = (float(v) for v in line.split(",")[:3])
            rows.append([r, length, t_start + t])
    return np.array(rows).reshape(-1, 3)


def plot_learning_curve(out: Path) -> Path | None:
    """Training episode returns (from the monitor logs) and evaluation returns against env steps."""
    import numpy as np

    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        print("matplotlib is not installed: no learning-curve plot", file=sys.stderr)
        return None
    fig = Figure(figsize=(7, 4))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    episodes = read_monitor(out / "monitor")
    if len(episodes):
        order = np.argsort(episodes[:, 2])
        returns, steps = episodes[order, 0], np.cumsum(episodes[order, 1])
        window = max(1, len(returns) // 20)
        smooth = np.convolve(returns, np.ones(window) / window, mode="valid")
        ax.plot(steps[window - 1 :], smooth, label=f"training (mean of {window} episodes)")
    evaluations = out / "evaluations.npz"
    if evaluations.is_file():
        data = np.load(evaluations)
        ax.errorbar(data["timesteps"], data["results"].mean(axis=1), yerr=data["results"].std(axis=1),
                    fmt="o-", label="evaluation seeds")  # fmt: skip
    ax.set_xlabel("env steps")
    ax.set_ylabel("episode return")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend()
    else:
        ax.text(0.5, 0.5, "no finished episode yet", transform=ax.transAxes, ha="center")
    path = out / "learning_curve.png"
    fig.savefig(path, dpi=100, bbox_inches="tight")
    return path


# ---------------------------------------------------------------------------------------------- command line
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--config", type=Path, default=Path("configs/ppo.yaml"))
    parser.add_argument("--env-id", default="EKFSLAM-v0")
    parser.add_argument("--timesteps", type=int, help="total env steps (overrides n_timesteps)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--n-envs", type=int, help="overrides n_envs")
    parser.add_argument("--out", type=Path, help="output folder (default runs/<env-id>_seed<seed>)")
    parser.add_argument(
        "--resume", type=Path, help="continue the run in this folder from its last checkpoint"
    )
    parser.add_argument("--hyperparams", nargs="*", default=[], metavar="KEY=VALUE",
                        help="override entries of the config, values parsed as YAML")  # fmt: skip
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (one is drawn only when stdout is a terminal)",
    )
    return parser


def main(argv: list[str] | None = None) -> Path:
    """``python train.py ...``: parse the command line and ``train``; returns the run folder."""
    parser = build_parser()
    args = parser.parse_args(argv)
    command = sys.argv[1:] if argv is None else list(argv)
    if args.resume is not None:
        try:
            env_id, seed, entry = read_run(args.resume)
        except FileNotFoundError as error:
            parser.error(str(error))
        if args.timesteps is not None:
            entry["n_timesteps"] = args.timesteps
        out = args.resume
    else:
        if not args.config.is_file():
            parser.error(f"config file {args.config} does not exist")
        env_id, seed = args.env_id, args.seed
        entry = resolve_entry(args.config, env_id, parse_hyperparams(args.hyperparams),
                              timesteps=args.timesteps, n_envs=args.n_envs)  # fmt: skip
        out = args.out or Path("runs") / f"{env_id}_seed{seed}"
    if int(entry["n_timesteps"]) <= 0:
        parser.error("--timesteps must be positive")
    if args.resume is not None and latest_checkpoint(out / "checkpoints") is None:
        parser.error(f"{out / 'checkpoints'} holds no checkpoint to resume from")
    return train(env_id, seed, entry, out, resume=args.resume is not None, progress=not args.no_progress,
                 command=command)  # fmt: skip
