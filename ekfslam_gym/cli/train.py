"""Train PPO on an EKFSLAM env from a config in rl-zoo3's format: ``ekfslam-train`` when installed, and the
repository's ``train.py`` runs this too.

    ekfslam-train --config ppo [--env-id ID] [--timesteps N] [--seed S] [--n-envs K]
                  [--out DIR] [--resume DIR] [--trained-agent MODEL] [--hyperparams KEY=VALUE ...]
                  [--no-progress]

``--config`` is a path or a packaged recipe by name (``ppo``, ``ppo_primitives.yaml``, ``configs/ppo.yaml``: the
repository's ``configs/*.yaml`` install with the package), found from any folder; the default is ``ppo``.

The config's format and the settings only this trainer reads (``train_settings``: evaluation, checkpoints,
``algo``, ``pretrain``) are described in ``ekfslam_gym.training.settings``; every setting, ``--hyperparams``
included, is checked before the run folder is created, and a bad one ends the command with one line naming it.
PPO collects whole rollouts of ``n_steps * n_envs`` env steps, so ``--timesteps`` is rounded up to them (the run
says so). The run folder's files are listed below (``ekfslam_gym.training.artefacts``).

``--resume DIR`` continues the run in DIR from its last checkpoint: weights, optimiser state, normalisation
statistics, timestep counter and random state (``ekfslam_gym.training.run``). ``--trained-agent MODEL`` (rl-zoo3's
flag) starts a new run from a saved policy, a shipped one too, instead of fresh weights: to fine-tune it on your
own map or under another reward (``ekfslam_gym.training.trained_agent``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from ..packaged import DEFAULT_CONFIG, config_names, resolve_config
from .common import command_line, command_parser, module_docstring


def build_parser() -> argparse.ArgumentParser:
    artefacts = module_docstring("ekfslam_gym.training.artefacts")  # imported, it would bring torch
    folder = artefacts[artefacts.index("The folder's files") :]
    parser = command_parser(
        "train", description=f"{__doc__}\n{folder}", formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--config", default=DEFAULT_CONFIG,
                        help="a training config (rl-zoo3 format): a path, or a packaged recipe by name "
                             f"({', '.join(config_names())}); default {DEFAULT_CONFIG}")  # fmt: skip
    parser.add_argument("--env-id", default="EKFSLAM-v0")
    parser.add_argument("--timesteps", type=int, help="total env steps (overrides n_timesteps)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--n-envs", type=int, help="overrides n_envs")
    parser.add_argument("--out", type=Path, help="output folder (default runs/<env-id>_seed<seed>)")
    parser.add_argument(
        "--resume", type=Path, help="continue the run in this folder from its last checkpoint"
    )
    parser.add_argument("-i", "--trained-agent", type=Path, metavar="MODEL",
                        help="start from this saved policy (its weights, optimiser state and normalisation "
                             "statistics) instead of fresh weights: a model's path, or an env id whose shipped "
                             "policy to fine-tune")  # fmt: skip
    parser.add_argument("--hyperparams", nargs="*", default=[], metavar="KEY=VALUE",
                        help="override entries of the config, values parsed as YAML")  # fmt: skip
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (one is drawn only when stdout is a terminal)",
    )
    return parser


@command_line("train")
def main(argv: Sequence[str] | None = None) -> int:
    """``ekfslam-train`` and ``python train.py``: parse the command line and ``train``; 0 when the run is done.
    A bad setting or file ends in one line naming it and exit status 2; training (torch, SB3) is imported only
    once the arguments are read."""
    parser = build_parser()
    args = parser.parse_args(argv)
    from ..training.artefacts import read_run
    from ..training.run import train
    from ..training.settings import SettingsError, parse_hyperparams, resolve_entry

    command = sys.argv[1:] if argv is None else list(argv)
    if args.resume is not None:
        try:
            env_id, seed, entry = read_run(args.resume)
        except (FileNotFoundError, ValueError) as error:  # no record, or not a complete one
            parser.error(str(error))
        if args.timesteps is not None:
            entry["n_timesteps"] = args.timesteps
        out = args.resume
    else:
        try:
            args.config = resolve_config(args.config)
            env_id, seed = args.env_id, args.seed
            entry = resolve_entry(args.config, env_id, parse_hyperparams(args.hyperparams),
                                  timesteps=args.timesteps, n_envs=args.n_envs)  # fmt: skip
        except (FileNotFoundError, SettingsError) as error:
            parser.error(str(error))
        out = args.out or Path("runs") / f"{env_id}_seed{seed}"
    try:
        trained_agent = None if args.trained_agent is None else trained_agent_file(args.trained_agent)
        train(env_id, seed, entry, out, resume=args.resume is not None, progress=not args.no_progress,
              command=command, trained_agent=trained_agent)  # fmt: skip
    except SettingsError as error:  # raised before anything is created
        parser.error(str(error))
    return 0


def trained_agent_file(model: Path) -> Path:
    """What ``--trained-agent`` names: a saved model's path (with or without ``.zip``) as given, else the shipped
    policy of the env id ``model`` (``ekfslam_gym.pretrained.shipped_policy_file``: the generalist for a v1
    layout id). ``SettingsError`` when it is neither."""
    from ..artefacts import ModelFiles
    from ..pretrained import shipped_policy_file
    from ..training.settings import SettingsError

    if ModelFiles.of(model).zip.is_file():
        return model
    try:
        return shipped_policy_file(str(model))
    except ValueError as error:
        raise SettingsError(f"--trained-agent {model}: neither a saved model ({ModelFiles.of(model).zip} is not a "
                            f"file) nor an env id with a shipped policy ({error})") from None  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
