"""A training run's settings: the config entry read from a YAML file in rl-zoo3's format, its overrides, and the
one validation of every setting (``validate_entry``), done before anything is created.

The config is rl-zoo3's own format, so ``python -m rl_zoo3.train -conf`` reads the same file: one entry per env
id with the PPO hyperparameters plus ``n_timesteps``, ``n_envs``, ``normalize`` (VecNormalize: false, true, or
its keyword arguments) and ``env_kwargs``. The settings only this package knows sit in a top-level
``train_settings`` section, keyed by env id, where rl-zoo3 does not look: ``vec_env`` (dummy | subproc),
``eval_freq``/``eval_episodes``/``eval_seed`` (model selection on evaluation seeds, never the held-out suite:
``ekfslam_gym.seeds``), ``checkpoint_freq`` (total env steps), ``torch_threads``, ``algo`` (rl-zoo3's name of
the algorithm: ``ppo``, the default, or ``ppo_lstm``, sb3-contrib's RecurrentPPO with ``policy: MlpLstmPolicy``
or ``MultiInputLstmPolicy``; ``ekfslam_gym.agents.ppo.ALGOS``; rl-zoo3 takes it as ``--algo``) and ``pretrain``
(planner-guided training: a planner's demonstrations cloned into the policy before PPO, ``PRETRAIN_DEFAULTS``;
absent means none; its ``keep_cloning`` keeps cloning steps up between PPO's updates, ``KEEP_CLONING_DEFAULTS``).
``--hyperparams`` overrides either kind. Class names in ``policy_kwargs`` (``features_extractor_class``,
``activation_fn``, ``optimizer_class``) may be given dotted, e.g. ``ekfslam_gym.agents.extractors.BeliefCNN`` or
``torch.nn.ReLU`` (``nn.ReLU`` too): they are imported when the model is built, and the record keeps the names.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml

from ekfslam_gym.agents.planners import PLANNERS, make_planner
from ekfslam_gym.agents.ppo import (  # noqa: F401  (resolve_policy_kwargs: where training reads it)
    ALGOS,
    CLASS_KWARGS,
    algo_class,
    resolve_policy_kwargs,
)
from ekfslam_gym.seeds import (
    DEMONSTRATION_SEED_START,
    EVAL_SEED_START,
    SELECTION_EPISODES,
    check_demonstration_seeds,
    check_not_held_out,
    selection_seeds,
)

NORMALIZE_DEFAULTS = {"norm_obs": True, "norm_reward": True}
TRAIN_KEYS = {
    "n_timesteps", "policy", "n_envs", "vec_env", "normalize", "env_kwargs", "eval_freq", "eval_episodes",
    "eval_seed", "checkpoint_freq", "torch_threads", "pretrain", "algo",
}  # fmt: skip
SETTINGS_SECTION = "train_settings"
SETTINGS_KEYS = {
    "vec_env", "eval_freq", "eval_episodes", "eval_seed", "checkpoint_freq", "torch_threads", "pretrain", "algo",
}  # fmt: skip
ENTRY_DEFAULTS: dict[str, Any] = {
    "n_timesteps": 100_000,
    "policy": "MlpPolicy",
    "n_envs": 1,
    "vec_env": "dummy",
    "normalize": False,
    "env_kwargs": {},
    "eval_freq": 0,
    "eval_episodes": SELECTION_EPISODES,
    "eval_seed": EVAL_SEED_START,
    "checkpoint_freq": 0,
    "torch_threads": 1,
    "pretrain": None,
    "algo": "ppo",
}
# The algorithm's constructor arguments the trainer sets itself, so an entry may not.
SET_BY_THE_TRAINER = ("self", "policy", "env", "seed", "tensorboard_log", "verbose", "_init_setup_model")
PRETRAIN_DEFAULTS: dict[str, Any] = {
    "planner": "greedy",  # the demonstrator (ekfslam_gym.agents.planners.PLANNERS)
    "planner_kwargs": None,  # keyword arguments of the demonstrator, e.g. {relocalize_std: 0.2} for frontier
    "episodes": 200,  # demonstration episodes, one per seed from ``seed``
    "seed": DEMONSTRATION_SEED_START,  # first demonstration seed: a training range, clear of the held-out and evaluation seeds
    "epochs": 10,  # passes over the demonstrations
    "batch_size": 256,  # pairs per minibatch; a recurrent policy's holds whole episodes, about as many pairs
    "learning_rate": 1.0e-3,  # Adam's, for cloning only (PPO keeps its own optimiser)
    "holdout": 0.1,  # fraction of the demonstration episodes held back to report accuracy on
    "value": True,  # also fit the value head to the demonstrations' discounted (normalised) returns
    "best_epoch": False,  # keep the epoch whose weights best predict the held-back episodes (early stopping)
    "path": None,  # a demonstrations .npz to reuse instead of collecting (same env id and env_kwargs; a reward may differ)
    "dagger_rounds": 0,  # DAgger rounds after cloning: the clone drives, the planner labels, clone again
    "dagger_episodes": 50,  # episodes per DAgger round, on the seeds after seed + episodes (path: those too)
    "keep_cloning": None,  # cloning steps kept up during PPO (ekfslam_gym.training.keep_cloning): {batches, learning_rate, decay}
}
KEEP_CLONING_DEFAULTS: dict[str, Any] = {
    "batches": 8,  # minibatches of the demonstrations after each rollout, one Adam step each
    "learning_rate": 3.0e-5,  # Adam's rate for them at the first rollout
    "decay": 1.0,  # the rate's factor per rollout (DAPG's lambda_1); 1 holds the clone near its teacher throughout
}


class SettingsError(ValueError):
    """A setting that cannot train: its message names the setting (or the file), what was wrong and what is
    allowed. The library raises it, never ``SystemExit``; a command line turns it into its usage error (exit 2)."""


# ---------------------------------------------------------------------------------------------- reading
def read_entry(config_path: Path, env_id: str) -> dict[str, Any]:
    """The config entry for ``env_id`` with its ``train_settings`` merged in, as the file has it (checked for
    misplaced and unknown settings only: ``validate_entry`` checks the values)."""
    try:
        data = yaml.safe_load(Path(config_path).read_text()) or {}
    except yaml.YAMLError as error:
        raise SettingsError(f"{config_path} is not valid YAML: {error}") from None
    if not isinstance(data, Mapping):
        raise SettingsError(f"{config_path} must map env ids to config entries, got {type(data).__name__}")
    data = dict(data)
    settings = data.pop(SETTINGS_SECTION, None) or {}
    if env_id not in data:
        raise SettingsError(f"{config_path} has no entry for {env_id!r}; it has {sorted(data)}")
    if not isinstance(data[env_id], Mapping) or not isinstance(settings, Mapping):
        raise SettingsError(f"{config_path}: the {env_id!r} entry and {SETTINGS_SECTION} must be mappings")
    entry = dict(data[env_id])
    misplaced = sorted(SETTINGS_KEYS & set(entry))
    if misplaced:
        raise SettingsError(
            f"{config_path}: {misplaced} in the {env_id!r} entry would reach PPO under rl-zoo3; "
            f"put them under '{SETTINGS_SECTION}: {{{env_id}: ...}}'"
        )
    extra = dict(settings.get(env_id) or {})
    unknown = sorted(set(extra) - SETTINGS_KEYS)
    if unknown:
        raise SettingsError(
            f"{config_path}: unknown {SETTINGS_SECTION} keys {unknown} for {env_id!r}; "
            f"known: {sorted(SETTINGS_KEYS)}"
        )
    entry.update(extra)
    return entry


def load_entry(config_path: Path, env_id: str) -> dict[str, Any]:
    """The config entry for ``env_id``, every training key defaulted and checked (``validate_entry``);
    SettingsError naming the file otherwise."""
    entry = read_entry(config_path, env_id)
    try:
        return validate_entry(entry, env_id)
    except SettingsError as error:
        raise SettingsError(f"{config_path}, entry {env_id!r}: {error}") from None


def resolve_entry(
    config: Path,
    env_id: str,
    hyperparams: dict[str, Any] | None = None,
    *,
    timesteps: int | None = None,
    n_envs: int | None = None,
) -> dict[str, Any]:
    """The entry a run trains with, before validation: the config's entry for ``env_id``, then
    ``hyperparams``, then the ``timesteps`` and ``n_envs`` overrides (the order of the command line's options)."""
    entry = read_entry(config, env_id)
    entry.update(hyperparams or {})
    if timesteps is not None:
        entry["n_timesteps"] = timesteps
    if n_envs is not None:
        entry["n_envs"] = n_envs
    return entry


def parse_hyperparams(pairs: list[str]) -> dict[str, Any]:
    """KEY=VALUE pairs, each VALUE parsed as YAML (so 3e-4, true, [64, 64] and {a: 1} work)."""
    out = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise SettingsError(f"--hyperparams takes KEY=VALUE pairs, got {pair!r}")
        out[key] = yaml.safe_load(value)
    return out


def schedule(value: Any) -> Any:
    """rl-zoo3's ``lin_X``: a learning rate falling linearly from X to 0 over the run; numbers pass through."""
    if isinstance(value, str) and value.startswith("lin_"):
        start = float(value[4:])
        return lambda progress_remaining: progress_remaining * start
    return value


# ---------------------------------------------------------------------------------------------- validation
def validate_entry(
    entry: Mapping[str, Any], env_id: str | None = None, seed: int | None = None
) -> dict[str, Any]:
    """``entry`` with every training key defaulted (``ENTRY_DEFAULTS``) and every setting checked, once, before a
    run creates anything: the step counts and frequencies, ``vec_env``, ``normalize``, ``algo``, ``policy`` and
    every hyperparameter against the algorithm's constructor, the schedules and class names, the evaluation
    seeds (and, with ``seed``, the training envs' seeds ``seed`` to ``seed + n_envs - 1``) against the held-out
    suite, ``env_kwargs`` by building the env (with ``env_id``), and ``pretrain``. SettingsError naming the
    setting otherwise. Idempotent: a validated entry passes unchanged."""
    if not isinstance(entry, Mapping):
        raise SettingsError(f"a config entry must be a mapping of settings, got {entry!r}")
    entry = dict(entry)
    for (
        key,
        default,
    ) in ENTRY_DEFAULTS.items():  # after the entry's own keys, as the record has always kept them
        entry.setdefault(key, dict(default) if isinstance(default, dict) else default)
    for key, low in (("n_timesteps", 1), ("n_envs", 1), ("eval_freq", 0), ("eval_episodes", 1), ("eval_seed", 0),
                     ("checkpoint_freq", 0), ("torch_threads", 1)):  # fmt: skip
        if not _is_int(entry[key]) or entry[key] < low:
            raise SettingsError(f"{key} must be an integer >= {low}, got {entry[key]!r}")
    if entry["vec_env"] not in ("dummy", "subproc"):
        raise SettingsError(f"vec_env must be dummy or subproc, got {entry['vec_env']!r}")
    if entry["algo"] not in ALGOS:
        raise SettingsError(f"algo must be one of {sorted(ALGOS)}, got {entry['algo']!r}")
    _check_normalize(entry["normalize"])
    _check_hyperparameters(entry)
    try:
        check_not_held_out(run_selection_seeds(entry), "eval_seed/eval_episodes: the evaluation seeds")
        if seed is not None:
            check_not_held_out(
                range(int(seed), int(seed) + entry["n_envs"]), f"seed {seed}: the training envs' seeds"
            )
    except ValueError as error:
        raise SettingsError(str(error)) from None
    if not isinstance(entry["env_kwargs"], Mapping):
        raise SettingsError(
            f"env_kwargs must be a mapping of gym.make arguments, got {entry['env_kwargs']!r}"
        )
    if env_id is not None:
        _check_env(env_id, entry["env_kwargs"])
    entry["pretrain"] = validate_pretrain(entry["pretrain"], entry)
    return entry


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _check_normalize(value: Any) -> None:
    """``normalize``: true, false, or VecNormalize's keyword arguments."""
    if isinstance(value, bool):
        return
    from stable_baselines3.common.vec_env import VecNormalize

    known = set(inspect.signature(VecNormalize.__init__).parameters) - {"self", "venv", "training"}
    if not isinstance(value, Mapping) or set(value) - known:
        raise SettingsError(
            f"normalize must be true, false or a mapping of VecNormalize's arguments {sorted(known)}, got {value!r}"
        )


def _check_hyperparameters(entry: Mapping[str, Any]) -> None:
    """Every key that is not a training key must be an argument of the algorithm (a misspelt one would reach its
    constructor as a TypeError after the run folder exists); ``policy`` one of its policies; the schedules and
    the dotted class names readable."""
    algo = algo_class(entry["algo"])
    known = set(inspect.signature(algo.__init__).parameters) - set(SET_BY_THE_TRAINER)
    unknown = sorted(set(entry) - TRAIN_KEYS - known)
    if unknown:
        raise SettingsError(
            f"unknown setting(s) {unknown} for {entry['algo']} ({algo.__name__}); training keys: "
            f"{sorted(TRAIN_KEYS)}; {algo.__name__}'s arguments: {sorted(known)}"
        )
    policy = entry["policy"]
    if isinstance(policy, str) and policy not in algo.policy_aliases:
        raise SettingsError(
            f"policy must be one of {sorted(algo.policy_aliases)} for {entry['algo']}, got {policy!r}"
        )
    for key in ("learning_rate", "clip_range"):
        value = entry.get(key)
        if isinstance(value, str):
            try:
                if not value.startswith("lin_"):
                    raise ValueError
                float(value[4:])
            except ValueError:
                raise SettingsError(
                    f"{key} must be a number or lin_X (a linear decay from X), got {value!r}"
                ) from None
    kwargs = entry.get("policy_kwargs")
    if kwargs is not None and not isinstance(kwargs, Mapping):
        raise SettingsError(f"policy_kwargs must be a mapping, got {kwargs!r}")
    try:
        resolve_policy_kwargs(kwargs)
    except ValueError as error:
        raise SettingsError(f"policy_kwargs: {error}") from None


def _check_env(env_id: str, env_kwargs: Mapping[str, Any]) -> None:
    """``env_kwargs`` build ``env_id`` (the env's own config checks name the field), on a layout that is not a
    held-out family (``ekfslam_gym.seeds.HELDOUT_FAMILIES``: never trained on)."""
    import gymnasium as gym

    import ekfslam_gym  # noqa: F401  (registers the env ids)
    from ekfslam_gym.seeds import check_training_family

    qualified = env_id if ":" in env_id else f"ekfslam_gym:{env_id}"
    try:
        env = gym.make(qualified, **dict(env_kwargs))
        config = getattr(env.unwrapped, "config", None)
        env.close()
        if config is not None:
            check_training_family(config.world.layout, "the training envs")
    except (TypeError, ValueError, KeyError, gym.error.Error) as error:
        raise SettingsError(f"env_kwargs for {env_id}: {error}") from None


def rollout_steps(entry: Mapping[str, Any]) -> int:
    """Env steps per rollout, ``n_steps`` (the algorithm's default when absent) times ``n_envs``: PPO collects
    whole rollouts, so a run trains a multiple of it."""
    n_steps = entry.get("n_steps")
    if n_steps is None:
        n_steps = (
            inspect.signature(algo_class(entry.get("algo", "ppo")).__init__).parameters["n_steps"].default
        )
    return int(n_steps) * int(entry["n_envs"])


def steps_trained(entry: Mapping[str, Any], done: int = 0) -> int:
    """The env steps a run of ``entry`` ends at, from ``done`` steps: ``n_timesteps`` rounded up to whole
    rollouts (``rollout_steps``) past ``done``."""
    per_rollout, total = rollout_steps(entry), int(entry["n_timesteps"])
    if total <= done:
        return done
    return done + -(-(total - done) // per_rollout) * per_rollout


def with_defaults(value: Any, defaults: Mapping[str, Any], name: str) -> dict[str, Any] | None:
    """A settings section ``name`` over its ``defaults``: None when absent or false, all defaults when true,
    else the mapping's keys over the defaults; ValueError for anything else or for a key not in ``defaults``."""
    if value is None or value is False:
        return None
    if value is True:
        value = {}
    if not isinstance(value, Mapping):
        raise SettingsError(f"{name} must be a mapping of {sorted(defaults)} (or absent), got {value!r}")
    unknown = sorted(set(value) - set(defaults))
    if unknown:
        raise SettingsError(f"unknown {name} keys {unknown}; known: {sorted(defaults)}")
    return {**defaults, **value}


def validate_pretrain(value: Any, entry: Mapping[str, Any] | None = None) -> dict[str, Any] | None:
    """The ``pretrain`` setting with its defaults filled in, or None when absent or false; SettingsError
    naming the key for anything else. With ``entry``, the demonstration seeds are also checked against its
    evaluation seeds (``eval_seed`` onwards, ``eval_episodes`` of them)."""
    settings = with_defaults(value, PRETRAIN_DEFAULTS, "pretrain")
    if settings is None:
        return None
    if settings["planner"] not in PLANNERS:
        raise SettingsError(f"pretrain.planner must be one of {list(PLANNERS)}, got {settings['planner']!r}")
    for key, low in (("episodes", 1), ("seed", 0), ("epochs", 1), ("batch_size", 1), ("dagger_rounds", 0),
                     ("dagger_episodes", 1)):  # fmt: skip
        if isinstance(settings[key], bool) or not isinstance(settings[key], int) or settings[key] < low:
            raise SettingsError(f"pretrain.{key} must be an integer >= {low}, got {settings[key]!r}")
    rate = settings["learning_rate"]
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not rate > 0:
        raise SettingsError(f"pretrain.learning_rate must be a positive number, got {rate!r}")
    holdout = settings["holdout"]
    if isinstance(holdout, bool) or not isinstance(holdout, (int, float)) or not 0 <= holdout < 1:
        raise SettingsError(f"pretrain.holdout must be a fraction in [0, 1), got {holdout!r}")
    for key in ("value", "best_epoch"):
        if not isinstance(settings[key], bool):
            raise SettingsError(f"pretrain.{key} must be true or false, got {settings[key]!r}")
    if settings["best_epoch"] and not holdout > 0:
        raise SettingsError(
            "pretrain.best_epoch picks an epoch by the held-back episodes: it needs holdout > 0"
        )
    kwargs = settings["planner_kwargs"]
    if kwargs is not None and not (isinstance(kwargs, Mapping) and all(isinstance(k, str) for k in kwargs)):
        raise SettingsError(f"pretrain.planner_kwargs must be a mapping of keyword arguments, got {kwargs!r}")
    if settings["path"] is not None and not isinstance(settings["path"], str):
        raise SettingsError(f"pretrain.path must be a file name or null, got {settings['path']!r}")
    settings["keep_cloning"] = validate_keep_cloning(settings["keep_cloning"])
    eval_seeds = range(0) if entry is None else run_selection_seeds(entry)
    try:
        check_demonstration_seeds(demonstration_seeds(settings, -1), eval_seeds)
    except ValueError as error:
        raise SettingsError(f"pretrain.seed/episodes: {error}") from None
    if entry is not None and "env_kwargs" in entry:
        action = (entry.get("env_kwargs") or {}).get("action") or {}
        kind = action.get("kind", "velocity") if isinstance(action, Mapping) else None
        if kind not in PLANNERS[settings["planner"]]:
            raise SettingsError(
                f"pretrain.planner {settings['planner']!r} demonstrates in action.kind "
                f"{' or '.join(map(repr, PLANNERS[settings['planner']]))}, but env_kwargs' action.kind is {kind!r}"
            )
    else:
        kind = PLANNERS[settings["planner"]][-1]
    if kwargs:
        try:  # the constructor checks its own arguments (the env is needed only at reset)
            make_planner(settings["planner"], kind, **kwargs)
        except (TypeError, ValueError) as error:
            raise SettingsError(f"pretrain.planner_kwargs: {error}") from None
    return settings


def validate_keep_cloning(value: Any) -> dict[str, Any] | None:
    """``pretrain.keep_cloning`` with its defaults filled in, or None when absent or false."""
    settings = with_defaults(value, KEEP_CLONING_DEFAULTS, "pretrain.keep_cloning")
    if settings is None:
        return None
    batches = settings["batches"]
    if isinstance(batches, bool) or not isinstance(batches, int) or batches < 1:
        raise SettingsError(f"pretrain.keep_cloning.batches must be an integer >= 1, got {batches!r}")
    rate, decay = settings["learning_rate"], settings["decay"]
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not rate > 0:
        raise SettingsError(f"pretrain.keep_cloning.learning_rate must be a positive number, got {rate!r}")
    if isinstance(decay, bool) or not isinstance(decay, (int, float)) or not 0 < decay <= 1:
        raise SettingsError(f"pretrain.keep_cloning.decay must be in (0, 1], got {decay!r}")
    return settings


def run_selection_seeds(entry: Mapping[str, Any]) -> range:
    """The evaluation seeds a run's entry selects its model on (``eval_seed`` onwards, ``eval_episodes``)."""
    return selection_seeds(
        entry.get("eval_seed", EVAL_SEED_START), entry.get("eval_episodes", SELECTION_EPISODES)
    )


def demonstration_seeds(settings: Mapping[str, Any], round_: int | None = None) -> range:
    """The planner's seeds (``round_`` None), those of DAgger round ``round_`` (0, 1, ...), or with ``round_`` -1
    all of them: one block of consecutive seeds from ``seed``."""
    first, n, per = int(settings["seed"]), int(settings["episodes"]), int(settings.get("dagger_episodes", 0))
    if round_ is None:
        return range(first, first + n)
    if round_ < 0:
        return range(first, first + n + int(settings.get("dagger_rounds", 0)) * per)
    start = first + n + round_ * per
    return range(start, start + per)
