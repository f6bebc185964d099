"""Evaluate agents on a fixed seed suite: per-episode metrics, IQM with bootstrap CIs, tables, plots and GIFs.

Usage::

    ekfslam-evaluate --agent greedy                       # the evaluation seeds, a text summary
    ekfslam-evaluate --agent greedy --seeds heldout       # the held-out suite: the final table
    ekfslam-evaluate --agent ppo --model models/ppo_EKFSLAM-v0.zip --json
    ekfslam-evaluate --compare --model models/ppo_EKFSLAM-v0.zip --table results.md --plot results.png
    ekfslam-evaluate --agent random,circle --seeds 0-9 --max-episode-steps 100 --gif gifs/
    ekfslam-evaluate --agent greedy --seeds 0-4 --export-tum tum/   # then: evo_ape tum ...
    ekfslam-evaluate --agent ppo --env-id EKFSLAM-Large-v0        # the shipped Large policy
    ekfslam-evaluate --agent myagents:BounceAgent,greedy          # your own agent beside greedy

``--agent ppo`` without ``--model`` evaluates the shipped policy of the env id. A saved model brings its env: with
no ``--env-id`` the evaluation runs on the env its training record names (EKFSLAM-v0 when no agent has a
record), and an ``--env-id`` other than the record's is an error unless ``--force``; ``--env-kwargs`` go on top
of the recorded settings (with a warning). ``--agent module:Class`` (or ``module:function``) evaluates an agent
of your own (``docs/writing-an-agent.md``).

The default seeds are the evaluation seeds (20000-20049); the held-out suite (10000-10049), for the final
table only, is asked for by name, ``--seeds heldout`` (``ekfslam_gym.seeds``). The metrics are described in
``ekfslam_gym.evaluation.episode_metrics``, the JSON output in ``ekfslam_gym.evaluation.report``. ``--export-tum DIR``
writes, per episode, ``<agent>_<seed>_true.tum`` and ``<agent>_<seed>_estimate.tum`` (TUM trajectories: the
poses after each step at step * dt s, z = 0, the heading as a quaternion about z; evo's APE on them without
alignment is the ``ate`` metric) and ``<agent>_<seed>_landmarks.csv`` (``ekfslam_gym.data.tum``).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..pretrained import DEFAULT_ENV_ID
from ..seeds import EVAL_SEEDS, HELD_OUT, SUITES, span, suite_name
from .common import (
    AGENT_NAMES,
    agent_from_flags,
    check_agent_interface,
    check_env_flags,
    command_line,
    command_parser,
    json_object,
    parse_seeds,
)

FORMATS = ("blocks", "table", "json")


def _build_parser() -> argparse.ArgumentParser:
    parser = command_parser(
        "evaluate",
        description=f"Evaluate agents on a seed suite (default: the evaluation seeds {span(EVAL_SEEDS)}; the "
        f"held-out suite {HELD_OUT} by name, --seeds heldout).",
    )
    parser.add_argument("--agent", default=None,
                        help=f"an agent or a comma-separated list (a comparison); one of {', '.join(AGENT_NAMES)}, or "
                             "module:Class (a class or factory of your own)")  # fmt: skip
    parser.add_argument("--compare", action="store_true",
                        help="compare random, circle, lawnmower, greedy (and ppo when --model is given)")  # fmt: skip
    parser.add_argument("--model", action="append", default=[],
                        help="saved PPO model (<model>.zip, statistics in <model>_vecnormalize.pkl); repeat it for "
                             "several training seeds, whose episodes are pooled into one 'ppo' row "
                             "unless --per-model; without it, --agent ppo evaluates the shipped policy of the env id")  # fmt: skip
    parser.add_argument(
        "--per-model", action="store_true", help="one row per --model instead of pooling them"
    )
    parser.add_argument("--env-id", default=None,
                        help="the env; default: the one a model's training record names, else EKFSLAM-v0")  # fmt: skip
    parser.add_argument("--force", action="store_true",
                        help="evaluate a model on an --env-id other than the one it was trained on")  # fmt: skip
    parser.add_argument("--env-kwargs", type=json_object, default=None,
                        help='config overrides as JSON, e.g. \'{"world": {"n_landmarks": 50}}\'; a trained policy '
                             "runs on its own training env settings (read beside the model) with these on top")  # fmt: skip
    parser.add_argument("--agent-kwargs", type=json_object, default=None,
                        help='constructor arguments per agent as JSON, e.g. \'{"circle": {"radius": 2.0}}\'')  # fmt: skip
    parser.add_argument("--seeds", type=parse_seeds, default=list(EVAL_SEEDS),
                        help=f"A-B (inclusive), A,B,C or a suite's name ({', '.join(SUITES)}); default the "
                             f"evaluation seeds {span(EVAL_SEEDS)}; heldout is {HELD_OUT}, for the final table only")  # fmt: skip
    parser.add_argument("--max-episode-steps", type=int, default=None, help="shorter episodes (smoke tests)")
    parser.add_argument("--format", choices=FORMATS, default=None,
                        help="what stdout shows: blocks (one per agent: IQM, CI and mean of every metric; the "
                             "default), table (one markdown table, a row per agent) or json (exactly one JSON "
                             "object)")  # fmt: skip
    parser.add_argument("--json", action="store_true", help="the same as --format json")
    parser.add_argument("--gif", metavar="DIR", default=None, help="write one GIF per episode to DIR")
    parser.add_argument("--gif-stride", type=int, default=2, help="keep every n-th frame in GIFs")
    parser.add_argument("--gif-scale", type=float, default=1.0, help="resize GIF frames by this factor")
    parser.add_argument("--plot", metavar="FILE", default=None, help="box plots of every metric")
    parser.add_argument("--table", metavar="FILE.md", default=None, help="markdown table of the aggregates")
    parser.add_argument("--episodes-json", metavar="FILE", default=None, help="write the per-episode metrics")
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bars (drawn only when stderr is a terminal)"
    )
    parser.add_argument("--smoother", action="store_true",
                        help="also smooth every episode with graph SLAM and report smoother_ate and "
                             "smoother_landmark_rmse beside the filter's ate and landmark_rmse")  # fmt: skip
    parser.add_argument("--export-tum", metavar="DIR", default=None,
                        help="write per episode <agent>_<seed>_true.tum and <agent>_<seed>_estimate.tum (TUM "
                             "trajectories for evo, stamped step * dt s) and <agent>_<seed>_landmarks.csv "
                             "(id, true x, y, estimated x, y, seen) to DIR")  # fmt: skip
    return parser


def _agent_entries(args: argparse.Namespace, parser: argparse.ArgumentParser) -> list[tuple[str, list[Any]]]:
    """(row label, agents whose episodes form that row); several agents in a row only for pooled PPO models."""
    from ekfslam_gym.agents import AGENTS, BASELINES, is_agent_name
    from ekfslam_gym.pretrained import shipped_policy_file

    if args.compare:
        names = list(BASELINES) + (["ppo"] if args.model else [])
    elif args.agent:
        names = [n.strip() for n in args.agent.split(",") if n.strip()]
    else:
        parser.error("give --agent NAME[,NAME...] or --compare")
    unknown = [n for n in names if not is_agent_name(n)]
    if unknown:
        parser.error(f"unknown agent(s) {unknown}; choose from {sorted(AGENTS)} or give module:Class")
    if len(set(names)) != len(names):
        parser.error("an agent is listed twice")
    per_agent = args.agent_kwargs or {}
    if not_objects := sorted(k for k, v in per_agent.items() if not isinstance(v, dict)):
        parser.error(
            f"--agent-kwargs: the value of {', '.join(map(repr, not_objects))} is not a JSON object; it must "
            'map agent names to their arguments, e.g. \'{"circle": {"radius": 2}}\''
        )
    if not_evaluated := sorted(set(per_agent) - set(names)):
        parser.error(f"--agent-kwargs: {not_evaluated} not among the agents evaluated, {names}")
    entries = []
    for name in names:
        kwargs = dict(per_agent.get(name, {}))
        if name == "ppo":
            if not args.model:  # the shipped policy of the env asked for
                try:
                    args.model = [str(shipped_policy_file(args.env_id or DEFAULT_ENV_ID))]
                except ValueError as error:
                    parser.error(f"--agent ppo without --model: {error}")
            models = [agent_from_flags(parser, "ppo", kwargs, model=path) for path in args.model]
            if args.per_model and len(models) > 1:
                names = [Path(p).with_suffix("").name for p in args.model]
                if len(set(names)) < len(names):  # e.g. every run's best_model.zip: name them by their run
                    names = [f"{Path(p).parent.name}/{n}" for p, n in zip(args.model, names)]
                entries += [(f"ppo[{n}]", [m]) for n, m in zip(names, models)]
            else:
                entries.append(("ppo", models))
        else:
            entries.append((name, [agent_from_flags(parser, name, kwargs)]))
    return entries


@command_line("evaluate")
def main(argv: Sequence[str] | None = None) -> int:
    parser = _build_parser()
    args = parser.parse_args(argv)
    from ..evaluation.aggregate import summary
    from ..evaluation.episode_metrics import ASSOCIATION_KEYS, METRIC_KEYS, NEES_STEP_BOUNDS
    from ..evaluation.report import json_safe, markdown_table, plot_results, text_summary
    from ..evaluation.rollout import evaluate_agent, merge_env_kwargs
    from ..evaluation.smoothing import SMOOTHER_KEYS
    from ..pretrained import resolve_env_id

    if args.json and args.format not in (None, "json"):
        parser.error(f"--json is --format json; it contradicts --format {args.format}")
    output = "json" if args.json else args.format or "blocks"
    entries = _agent_entries(args, parser)
    if any(label.startswith("ppo") for label, _ in entries):
        import torch

        torch.set_num_threads(1)  # small MLP policies: threads only contend with the other cores' work

    try:
        args.env_id = resolve_env_id([a for _, group in entries for a in group], args.env_id, args.force)
    except ValueError as error:
        parser.error(str(error))
    check_env_flags(parser, args.env_id, args.env_kwargs)
    for label, agent_list in entries:
        for agent in agent_list:
            trained_kwargs = getattr(agent, "trained_env_kwargs", None)
            evaluated = merge_env_kwargs(trained_kwargs, args.env_kwargs)
            check_agent_interface(parser, label, agent, args.env_id, evaluated)
            if trained_kwargs is not None and evaluated != dict(trained_kwargs):
                print(
                    f"warning: {agent!r} was trained with env_kwargs {trained_kwargs}, evaluated with "
                    f"{evaluated} (--env-kwargs goes on top of the training settings, section by section)",
                    file=sys.stderr,
                )

    episodes: dict[str, list[dict[str, float]]] = {}
    for label, agent_list in entries:
        rows: list[dict[str, float]] = []
        for k, agent in enumerate(agent_list):
            tag = label if len(agent_list) == 1 else f"{label}{k}"
            # A trained policy runs on the env settings it was trained with (its action interface, limits,
            # ...), read from the record beside the model; --env-kwargs goes on top, section by section, for every agent.
            env_kwargs = merge_env_kwargs(getattr(agent, "trained_env_kwargs", None), args.env_kwargs)
            rows += evaluate_agent(
                agent, args.env_id, args.seeds, env_kwargs, max_episode_steps=args.max_episode_steps,
                gif_dir=args.gif, gif_stride=args.gif_stride, gif_scale=args.gif_scale, label=tag,
                progress=not args.no_progress,
                smoother=args.smoother, tum_dir=args.export_tum,
            )  # fmt: skip
        episodes[label] = rows
    keys = METRIC_KEYS + (SMOOTHER_KEYS if args.smoother else ())
    # Unknown data association (filter.association in the env settings) adds its counts to every row.
    every_row = [row for rows in episodes.values() for row in rows]
    if every_row and all(key in row for row in every_row for key in ASSOCIATION_KEYS):
        keys += ASSOCIATION_KEYS
    summaries = {label: summary(label, rows, keys=keys) for label, rows in episodes.items()}

    if args.table:
        path = Path(args.table)
        path.parent.mkdir(parents=True, exist_ok=True)
        seeds = args.seeds
        names = {"heldout": " (the held-out suite)", "eval": " (the evaluation seeds)"}
        named = names.get(suite_name(seeds) or "", "")
        path.write_text(
            f"`{args.env_id}`, seeds {span(seeds)}{named}, {len(seeds)} episodes per agent.\n\n"
            + markdown_table(summaries, keys)
        )
    if args.plot:
        plot_results(episodes, args.plot, keys)
    if args.episodes_json:
        Path(args.episodes_json).write_text(json.dumps(json_safe(episodes), indent=1))

    if output == "json":
        out: Any = next(iter(summaries.values())) if len(summaries) == 1 else summaries
        print(json.dumps(json_safe(out), allow_nan=False))
    elif output == "table":
        print(f"`{args.env_id}`, {len(args.seeds)} seeds ({args.seeds[0]}..{args.seeds[-1]})\n")
        print(markdown_table(summaries, keys), end="")
    else:
        print(f"{args.env_id}, {len(args.seeds)} seeds ({args.seeds[0]}..{args.seeds[-1]})")
        for s in summaries.values():
            print(text_summary(s))
        print(f"pose NEES per-step 95 % bounds: [{NEES_STEP_BOUNDS[0]:.3f}, {NEES_STEP_BOUNDS[1]:.2f}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
