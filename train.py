"""Train PPO on an EKFSLAM env from configs/ppo.yaml: the command line of ``ekfslam_gym.agents.training`` (see its docstring).

    python train.py --config configs/ppo.yaml [--env-id ID] [--timesteps N] [--seed S] [--n-envs K]
                    [--out DIR] [--resume DIR] [--hyperparams KEY=VALUE ...] [--no-progress]

The implementation lives in the installed package (``ekfslam_gym.agents.training``) so that code without this repository's
root on its path (a pip install, the sweep's Ray workers) can train too; this script keeps the old names. Run as a
script, bad input ends in one line on stderr and exit status 2 (``EKFSLAM_DEBUG=1`` for the traceback:
``ekfslam_gym.cli.common.command_line``); ``main`` imported from here raises as it always did.
"""

from __future__ import annotations

from pathlib import Path

from ekfslam_gym.agents.training import (
    NORMALIZE_DEFAULTS,
    SETTINGS_KEYS,
    SETTINGS_SECTION,
    TRAIN_KEYS,
    build_callbacks,
    build_parser,
    latest_checkpoint,
    load_entry,
    main,
    make_envs,
    parse_hyperparams,
    plot_learning_curve,
    read_monitor,
    read_run,
    resolve_entry,
    save_checkpoint,
    save_with_stats,
    schedule,
    train,
    versions,
)

__all__ = [
    "NORMALIZE_DEFAULTS",
    "SETTINGS_KEYS",
    "SETTINGS_SECTION",
    "TRAIN_KEYS",
    "Path",
    "build_callbacks",
    "build_parser",
    "check_settings",
    "latest_checkpoint",
    "load_entry",
    "main",
    "make_envs",
    "parse_hyperparams",
    "plot_learning_curve",
    "read_monitor",
    "read_run",
    "resolve_entry",
    "save_checkpoint",
    "save_with_stats",
    "schedule",
    "train",
    "versions",
]

# What train() passes to the algorithm itself: an entry may not set these.
_PASSED_BY_TRAIN = {"env", "seed", "tensorboard_log", "verbose", "_init_setup_model"}


def check_settings(config: Path, env_id: str, hyperparams: list[str]) -> None:
    """Refuse a key that is neither this script's (``TRAIN_KEYS``) nor an argument of the algorithm (a misspelt
    ``--hyperparams learning_rat=...``) before anything is created; ValueError naming the flag or the config."""
    import difflib
    import inspect

    from ekfslam_gym.agents.ppo import algo_class

    overrides = parse_hyperparams(hyperparams)
    entry = resolve_entry(config, env_id, overrides)
    algo = entry.get("algo", "ppo")
    takes = set(inspect.signature(algo_class(algo)).parameters) - _PASSED_BY_TRAIN
    allowed = sorted(TRAIN_KEYS | takes)
    for key in entry:
        if key not in allowed:
            where = "--hyperparams" if key in overrides else f"{config} (entry {env_id})"
            close = difflib.get_close_matches(key, allowed, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ValueError(
                f"{where}: unknown setting {key!r} for algo {algo}{hint} Known: {', '.join(allowed)}"
            )


def _command_line(argv: list[str] | None = None) -> Path:
    """``main`` with the settings checked first (a fresh run; ``--resume`` trains with what the run recorded)."""
    args = build_parser().parse_args(argv)
    if args.resume is None and args.config.is_file():
        check_settings(args.config, args.env_id, args.hyperparams)
    return main(argv)


if __name__ == "__main__":
    from ekfslam_gym.cli.common import command_line

    command_line("train", prog=build_parser().prog)(_command_line)()
