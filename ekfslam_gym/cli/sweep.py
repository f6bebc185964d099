"""Train and evaluate PPO over env ids x training seeds on Ray, and tabulate the evaluations.

Usage::

    ekfslam-sweep --env-ids EKFSLAM-v0 --seeds 0-4 --timesteps 200000 --out runs/sweep
    ekfslam-sweep --env-ids EKFSLAM-v0,EKFSLAM-Loop-v0 --seeds 0-2 --address auto --json

Each (env id, seed) trains as ``python train.py --config CONFIG --env-id ID --seed S`` would (into
``OUT/<env-id>_seed<S>/``) and its final model is evaluated on ``--eval-seeds`` (default the evaluation seeds
20000-20009; the held-out suite 10000-10049 is refused: ``ekfslam_gym.seeds``). Finished trials are skipped,
interrupted ones resume (see ``ekfslam_gym.training.sweep``). ``OUT/sweep.json`` and ``OUT/sweep.md`` hold, per
env id, the IQM with its 95 % bootstrap CI of every metric pooled over the seeds' episodes and per seed
(``ekfslam_gym.evaluation.aggregate``).
Progress goes to stderr; with ``--json`` the last line of stdout is the JSON object of ``sweep.json``:
``{"env_ids", "seeds", "eval_seeds", "timesteps" (per env id), "wall_seconds", "trained_steps", "steps_per_second",
"failed", "results": {env_id: {"pooled": summary, "seeds": {seed: summary}}}}`` with each summary as the
evaluate command's (``ekfslam_gym.evaluation.report``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..evaluation.aggregate import summary
from ..evaluation.episode_metrics import METRIC_KEYS
from ..evaluation.report import json_safe, markdown_table
from ..packaged import DEFAULT_CONFIG, resolve_config
from ..seeds import HELD_OUT, SELECTION_SEEDS, check_not_held_out, span
from .common import command_line, command_parser, parse_seeds


def _build_parser() -> argparse.ArgumentParser:
    parser = command_parser(
        "sweep",
        description="Train PPO over env ids x seeds on Ray (local or a cluster) and tabulate the evaluations.",
    )
    parser.add_argument("--env-ids", default="EKFSLAM-v0", help="env ids, comma-separated")
    parser.add_argument("--seeds", type=parse_seeds, required=True, help="training seeds, A-B or A,B,C")
    parser.add_argument("--config", default=DEFAULT_CONFIG,
                        help="training config in rl-zoo3's format, as train.py's: a path or a packaged recipe's name "
                             f"(default {DEFAULT_CONFIG})")  # fmt: skip
    parser.add_argument("--timesteps", type=int, help="env steps per trial (overrides n_timesteps)")
    parser.add_argument("--hyperparams", nargs="*", default=[], metavar="KEY=VALUE",
                        help="override entries of the config, values parsed as YAML (as train.py's)")  # fmt: skip
    parser.add_argument("--eval-seeds", type=parse_seeds, default=None,
                        help=f"evaluation seeds, default {span(SELECTION_SEEDS)}; never the held-out {HELD_OUT}")  # fmt: skip
    parser.add_argument(
        "--out", type=Path, default=Path("runs/sweep"), help="sweep folder (default runs/sweep)"
    )
    parser.add_argument("--address", default=None,
                        help="join a running Ray cluster ('auto' or 'ray://HOST:PORT'); default: a local Ray")  # fmt: skip
    parser.add_argument("--workers", type=int, default=None,
                        help="CPUs of the local Ray, one trial each (default: the machine's cores)")  # fmt: skip
    parser.add_argument(
        "--json", action="store_true", help="print the sweep's JSON object as stdout's last line"
    )
    return parser


def tabulate(results: Sequence[Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per env id: the summary of all seeds' episodes pooled, and one summary per seed (in seed order)."""
    tables: dict[str, dict[str, Any]] = {}
    for env_id in dict.fromkeys(r["env_id"] for r in results):
        runs = sorted((r for r in results if r["env_id"] == env_id), key=lambda r: r["seed"])
        pooled = [e for r in runs for e in _episodes(r)]
        tables[env_id] = {
            "pooled": summary("pooled", pooled),
            "seeds": {str(r["seed"]): summary(f"seed {r['seed']}", _episodes(r)) for r in runs},
        }
    return tables


def _episodes(result: Mapping[str, Any]) -> list[dict[str, float]]:
    """A trial's episodes with JSON's nulls back as NaN (the aggregates leave NaN out)."""
    return [{k: float("nan") if v is None else v for k, v in e.items()} for e in result["episodes"]]


def markdown(report: Mapping[str, Any]) -> str:
    """``sweep.md``: one table per env id, the pooled row first, then one row per training seed."""
    parts = []
    seeds = report["eval_seeds"]
    for env_id, table in report["results"].items():
        rows = {"pooled": table["pooled"], **{f"seed {s}": t for s, t in table["seeds"].items()}}
        text = markdown_table(rows, METRIC_KEYS).replace("| agent |", "| training seed |", 1)
        parts.append(
            f"## `{env_id}`\n\n{len(table['seeds'])} training seeds x {len(seeds)} evaluation seeds "
            f"({seeds[0]}-{seeds[-1]}), final models after {report['timesteps'][env_id]} env steps; the pooled row "
            f"pools every seed's episodes.\n\n{text}"
        )
    return "\n".join(parts)


@command_line("sweep")
def main(argv: Sequence[str] | None = None) -> int:
    parser = _build_parser()
    args = parser.parse_args(argv)
    from ..training import settings, sweep

    env_ids = [e.strip() for e in args.env_ids.split(",") if e.strip()]
    if not env_ids:
        parser.error("--env-ids names no env id")
    eval_seeds = tuple(args.eval_seeds or SELECTION_SEEDS)
    try:
        check_not_held_out(eval_seeds, "--eval-seeds")
    except ValueError as error:
        parser.error(str(error))
    if args.address is not None and args.workers is not None:
        parser.error("--workers sizes the local Ray; with --address the cluster's size decides")
    if args.workers is not None and args.workers < 1:
        parser.error("--workers must be at least 1")
    try:  # a packaged recipe by name, or a path; absolute, as the trials may run in other folders (Ray workers)
        args.config = resolve_config(args.config).resolve()
    except FileNotFoundError as error:
        parser.error(str(error))
    try:
        hyperparams = settings.parse_hyperparams(args.hyperparams)
    except settings.SettingsError as error:
        parser.error(str(error))

    trials = []
    for env_id in env_ids:
        try:  # every trial's settings (the config's entry, --hyperparams), checked before any runs
            entry = settings.resolve_entry(args.config, env_id, hyperparams, timesteps=args.timesteps)
            entry = settings.validate_entry(entry, env_id)
            for seed in args.seeds:
                check_not_held_out(
                    range(seed, seed + entry["n_envs"]), f"training seed {seed}: its envs' seeds"
                )
        except ValueError as error:
            parser.error(f"{env_id}: {error}")
        for seed in args.seeds:
            command = ["--config", str(args.config), "--env-id", env_id, "--seed", str(seed),
                       "--out", str(args.out / f"{env_id}_seed{seed}"), "--timesteps", str(entry["n_timesteps"]),
                       *(["--hyperparams", *args.hyperparams] if args.hyperparams else [])]  # fmt: skip
            trials.append(sweep.Trial(env_id, seed, entry, args.out, eval_seeds, tuple(command)))

    started = time.perf_counter()
    results, failures = sweep.run_trials(trials, address=args.address, workers=args.workers)
    wall = time.perf_counter() - started
    trained = sum(r["trained_steps"] for r in results)
    report = {
        "env_ids": env_ids,
        "seeds": list(args.seeds),
        "eval_seeds": list(eval_seeds),
        "timesteps": {t.env_id: int(t.entry["n_timesteps"]) for t in trials},
        "wall_seconds": wall,
        "trained_steps": trained,
        "steps_per_second": trained / wall if trained else None,
        "failed": [{"trial": t.name, "error": e} for t, e in failures],
        "results": tabulate(results),
    }
    report = json_safe(report)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "sweep.json").write_text(json.dumps(report, indent=1, allow_nan=False))
    (args.out / "sweep.md").write_text(markdown(report))
    print(f"{len(results)} trials ({trained} env steps trained in {wall:.1f} s); tables in "
          f"{args.out / 'sweep.md'}", file=sys.stderr)  # fmt: skip
    if args.json:
        print(json.dumps(report, allow_nan=False), flush=True)
    else:
        print(markdown(report), end="")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
