"""The standard protocol in one command: an agent on the held-out suite of every env with reference rows (the
v0 ids; or ``--env-ids``), IQM with 95 % bootstrap CIs, beside the reference rows (the baselines and shipped
policies of the last full run, ``ekfslam_gym/benchmark/reference.json``). Markdown on stdout (``--json``: one
JSON object); ``--out DIR`` writes ``benchmark.md`` and ``benchmark.json``. ``--suite generalisation`` runs
the generalisation suite instead (``ekfslam_gym.benchmark.generalisation``).

Usage::

    ekfslam-benchmark --agent frontier --env-ids EKFSLAM-v0          # should reproduce the frontier reference row
    ekfslam-benchmark --agent ppo                                    # the shipped policy of every env
    ekfslam-benchmark --model runs/x/best_model.zip                  # a saved model, on the env of its record
    ekfslam-benchmark --agent myagents:make_agent --quick            # your own agent, 5 seeds (a smoke test)
    ekfslam-benchmark --suite generalisation --out results           # every agent on the v1 ids and families
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..benchmark import QUICK_EPISODES, markdown, reference_rows, run
from ..benchmark.generalisation import SEEDS_PER_CASE
from ..seeds import HELD_OUT
from .common import command_line, command_parser, json_object


def _build_parser() -> argparse.ArgumentParser:
    parser = command_parser(
        "benchmark",
        description=f"An agent on the held-out suite ({HELD_OUT}) of each env beside the reference rows.",
    )
    parser.add_argument("--agent", default=None,
                        help="a registered agent (ppo alone: the shipped policy of each env) or module:Class / "
                             "module:function of your own")  # fmt: skip
    parser.add_argument("--model", default=None, help="a saved model (<model>.zip with its record beside it)")
    parser.add_argument(
        "--agent-kwargs", type=json_object, default=None, help="constructor arguments as JSON"
    )
    parser.add_argument("--env-ids", default=None,
                        help="comma-separated env ids; default those with reference rows, the v0 ids (with "
                             "--model: its record's)")  # fmt: skip
    parser.add_argument("--force", action="store_true", help="run a model on env ids other than its own")
    parser.add_argument("--quick", action="store_true",
                        help=f"the suite's first {QUICK_EPISODES} seeds: a smoke test, not a result")  # fmt: skip
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of Markdown")
    parser.add_argument("--out", type=Path, default=None, help="write benchmark.md and benchmark.json here")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars on stderr")
    parser.add_argument("--suite", choices=["generalisation"], default=None,
                        help="generalisation: every baseline and shipped policy on every v1 layout id, the "
                             "training families' held-out seeds and the held-out families (no --agent; --out "
                             "DIR keeps a CSV of the episodes, and a run stopped early resumes from it)")  # fmt: skip
    parser.add_argument("--suite-seeds", type=int, default=None,
                        help=f"held-out seeds per env of the suite (default {SEEDS_PER_CASE}; --quick: 1)")  # fmt: skip
    return parser


def _factory(args: argparse.Namespace, parser: argparse.ArgumentParser) -> tuple[Any, str, list[str] | None]:
    """(make(env_id) -> (agent, env settings), the row's label, the env ids a model fixes or None)."""
    from ekfslam_gym.agents import AGENTS, is_agent_name, make_agent
    from ekfslam_gym.pretrained import shipped_policy_file

    kwargs = args.agent_kwargs or {}
    if not isinstance(kwargs, dict):
        parser.error("--agent-kwargs must be a JSON object, e.g. '{\"radius\": 2}'")
    if args.model is not None:
        if args.agent not in (None, "ppo"):
            parser.error("--model is a ppo policy: give it without --agent (or with --agent ppo)")
        agent = make_agent("ppo", model_path=args.model, **kwargs)
        return (lambda env_id: (agent, agent.trained_env_kwargs)), "ppo", [agent.trained_env_id]
    if args.agent is None:
        parser.error("give --agent NAME (or module:Class) or --model PATH")
    if not is_agent_name(args.agent):
        parser.error(f"unknown agent {args.agent!r}; choose from {sorted(AGENTS)} or give module:Class")
    if args.agent == "ppo":

        def shipped(env_id: str) -> tuple[Any, Any]:
            agent = make_agent("ppo", model_path=shipped_policy_file(env_id), **kwargs)
            return agent, agent.trained_env_kwargs

        return shipped, "ppo", None
    kind = getattr(AGENTS.get(args.agent), "action_kind", None)
    if kind is not None and str(kind) != "velocity":
        parser.error(f"--agent {args.agent} acts in action.kind {kind}, and the benchmark runs every id with its "
                     "registered settings, in velocity commands; ekfslam-evaluate --env-kwargs runs it in its own")  # fmt: skip
    # A registered agent is labelled by its registered name, one of your own (module:Class) by its ``name``.
    label = (
        args.agent
        if ":" not in args.agent
        else str(getattr(make_agent(args.agent, **kwargs), "name", args.agent))
    )
    return (lambda env_id: (make_agent(args.agent, **kwargs), None)), label, None


@command_line("benchmark")
def main(argv: Sequence[str] | None = None) -> int:
    import gymnasium as gym

    import ekfslam_gym  # noqa: F401  (registers the ids)

    parser = _build_parser()
    args = parser.parse_args(argv)
    if args.suite is not None:
        return _suite(args, parser)
    make, label, model_ids = _factory(args, parser)
    registered = sorted(i for i in gym.registry if i.startswith("EKFSLAM"))
    if args.env_ids is None:
        env_ids = [i for i in model_ids if i] if model_ids else [i for i in registered if reference_rows(i)]
    else:
        env_ids = [e.strip() for e in args.env_ids.split(",") if e.strip()]
    if unknown := [e for e in env_ids if e.split(":")[-1] not in gym.registry]:
        parser.error(f"unknown env id(s) {unknown}; registered: {registered}")
    if model_ids and not args.force and (other := [e for e in env_ids if e.split(":")[-1] not in model_ids]):
        parser.error(f"the model was trained on {model_ids[0]}, not {', '.join(other)}: leave out --env-ids or "
                     "add --force")  # fmt: skip
    if label == "ppo":
        import torch

        from ekfslam_gym.pretrained import shipped_policy_file

        torch.set_num_threads(1)
        for env_id in env_ids if model_ids is None else ():
            try:
                shipped_policy_file(env_id)
            except ValueError as error:
                parser.error(f"--agent ppo: {error}")
    report = run(make, env_ids, label, quick=args.quick, progress=not args.no_progress)
    text = markdown(report)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "benchmark.md").write_text(text)
        (args.out / "benchmark.json").write_text(json.dumps(report, indent=1, allow_nan=False))
    print(json.dumps(report, allow_nan=False) if args.json else text, end="\n" if args.json else "")
    return 0


def _suite(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """``--suite generalisation`` (``ekfslam_gym.benchmark.generalisation``)."""
    from ..benchmark.generalisation import run_suite

    if args.agent is not None or args.model is not None or args.env_ids is not None:
        parser.error("--suite runs every baseline and shipped policy on its own envs: leave out --agent, "
                     "--model and --env-ids")  # fmt: skip
    report = None if args.no_progress else (lambda line: print(line, file=sys.stderr, flush=True))
    if args.suite_seeds is not None and args.suite_seeds < 1:
        parser.error(f"--suite-seeds must be >= 1, got {args.suite_seeds}")
    print(run_suite(quick=args.quick, seeds_per_case=args.suite_seeds, out=args.out, progress=report), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
