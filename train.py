"""Train PPO on an EKFSLAM env from configs/ppo.yaml: the command line of ``ekfslam_gym.agents.training`` (see its docstring).

    python train.py --config configs/ppo.yaml [--env-id ID] [--timesteps N] [--seed S] [--n-envs K]
                    [--out DIR] [--resume DIR] [--hyperparams KEY=VALUE ...] [--no-progress]

The implementation lives in the installed package (``ekfslam_gym.agents.training``) so that code without this repository's
root on its path (a pip install, the sweep's Ray workers) can train too; this script keeps the old names.
"""

from __future__ import annotations

from pathlib import Path

from ekfslam_gym.agents.training import (
    NORMALIZE_DEFAULTS,
    SETTINGS_KEYS,
    SETTINGS_SECTION,
    TRAIN_KEYS,
    build_callbacks,
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

if __name__ == "__main__":
    from ekfslam_gym.cli.common import command_line

    command_line("train")(main)()  # bad input: one line on stderr, exit 2 (EKFSLAM_DEBUG=1: the traceback)
