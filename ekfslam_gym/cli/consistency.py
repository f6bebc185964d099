"""The filter's consistency under agents' driving, per agent and filter variant (see
``ekfslam_gym.evaluation.consistency``): pose NEES, map NEES and NIS per step against their chi-squared bands.

ekfslam-consistency [--env-id EKFSLAM-v0] [--agents random,circle] [--filters ekf,fej,iekf]
    [--seeds 0-49] [--steps 200] [--env-kwargs JSON] [--model PATH] [--json] [--plot FILE.png]

Each value is the sum over runs divided by the summed degrees of freedom (1 when consistent); "inside" is the
fraction of steps within the 95 % band. The default seeds 0-49 are neither the held-out suite nor the
evaluation seeds. Every control step is sampled: a policy whose training record (beside ``--model``) has macro
actions (``action.kind`` primitives, held N steps) runs with that action kind held 1 step, asked every N steps
and its action repeated in between, which drives exactly as the macro action does. ``--steps`` counts control
steps.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from ..evaluation.consistency import QUANTITIES, ConsistencyRun, run_consistency
from ..filter.settings import VARIANTS
from .common import (
    agent_from_flags,
    check_agent_interface,
    check_env_flags,
    command_line,
    command_parser,
    json_object,
    parse_seeds,
)


def _build_parser() -> argparse.ArgumentParser:
    parser = command_parser(
        "consistency", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env-id", default="EKFSLAM-v0")
    parser.add_argument(
        "--agents", default="random,circle", help="comma-separated agent names (module:Class for your own)"
    )
    parser.add_argument(
        "--filters", default="ekf", help=f"comma-separated filter variants ({', '.join(VARIANTS)})"
    )
    parser.add_argument("--seeds", default="0-49", type=parse_seeds, help="one run per seed: A-B or A,B,C")
    parser.add_argument("--steps", type=int, default=200, help="control steps per run")
    parser.add_argument("--env-kwargs", type=json_object, default=None, help="config overrides as JSON")
    parser.add_argument(
        "--model",
        default=None,
        help="the saved policy, for the ppo agent (default: the shipped policy of --env-id)",
    )
    parser.add_argument("--json", action="store_true", help="one JSON object on the last line of stdout")
    parser.add_argument("--plot", default=None, metavar="FILE.png", help="the three quantities over time")
    return parser


def plot_runs(runs: list[ConsistencyRun], path: str) -> None:
    """One panel per quantity: each run's normalised value over time and its 95 % band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(QUANTITIES), 1, figsize=(11, 8), sharex=True, layout="constrained")
    titles = {"pose_nees": "pose NEES / 3", "map_nees": "map NEES / dof", "nis": "NIS / dof"}
    for ax, quantity in zip(axes, QUANTITIES):
        for run in runs:
            (line,) = ax.plot(run.normalised(quantity), lw=1.0, label=run.label)
            lo, hi = run.bands(quantity)
            ax.fill_between(range(lo.size), lo, hi, color=line.get_color(), alpha=0.08, lw=0)
        ax.axhline(1.0, color="k", lw=0.6)
        ax.set_ylabel(titles[quantity])
        ax.set_yscale("log")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside right upper", fontsize=8)
    axes[-1].set_xlabel("step")
    fig.savefig(path, dpi=110)
    plt.close(fig)


@command_line("consistency")
def main(argv: Sequence[str] | None = None) -> int:
    parser = _build_parser()
    args = parser.parse_args(argv)
    import gymnasium as gym

    from ekfslam_gym.agents import AGENTS, is_agent_name
    from ekfslam_gym.evaluation.rollout import merge_env_kwargs
    from ekfslam_gym.pretrained import shipped_policy_file

    agents = [a.strip() for a in args.agents.split(",") if a.strip()]
    filters = [f.strip() for f in args.filters.split(",") if f.strip()]
    if unknown := [a for a in agents if not is_agent_name(a)]:
        parser.error(f"unknown agent(s) {unknown}; choose from {sorted(AGENTS)} or give module:Class")
    if unknown := [f for f in filters if f not in VARIANTS]:
        parser.error(f"unknown filter variant(s) {unknown}; choose from {list(VARIANTS)}")
    if args.steps < 1:
        parser.error("--steps must be positive")
    if "ppo" in agents and not args.model:  # the shipped policy of the env id
        try:
            args.model = str(shipped_policy_file(args.env_id))
        except ValueError as error:
            parser.error(f"--agents ppo without --model: {error}")
    check_env_flags(parser, args.env_id, args.env_kwargs)

    runs = []
    for name in agents:
        agent = agent_from_flags(parser, name, {}, model=args.model if name == "ppo" else None)
        # A policy runs on its recorded env settings (its observation above all), as evaluate runs it; the
        # step limit is --steps and a macro action is sampled per control step.
        trained = dict(getattr(agent, "trained_env_kwargs", None) or {})
        trained.pop("max_episode_steps", None)
        trained_action = dict(trained.get("action") or {})
        decide_every = int(trained_action.get("hold", 1))
        if trained_action.get("kind", "velocity") == "waypoint":
            parser.error("a waypoint policy's macro steps cannot be sampled per control step")
        evaluated = merge_env_kwargs(trained, args.env_kwargs)
        check_agent_interface(parser, name, agent, args.env_id, evaluated, flag="--agents")
        for variant in filters:
            overrides = dict(evaluated)  # each variant replaces its own sections, never evaluated's
            overrides["filter"] = {**overrides.get("filter", {}), "variant": variant}
            if trained_action:
                overrides["action"] = {**overrides.get("action", {}), "hold": 1}

            def factory(overrides=overrides):
                return gym.make(args.env_id, max_episode_steps=args.steps, **overrides)

            runs.append(
                run_consistency(factory, agent, args.seeds, args.steps, f"{name} / {variant}", decide_every)
            )
            print(f"done: {name} / {variant}", file=sys.stderr)

    summaries = [run.summary() for run in runs]
    if args.plot:
        plot_runs(runs, args.plot)
    if args.json:
        print(
            json.dumps(
                {"env_id": args.env_id, "seeds": len(args.seeds), "steps": args.steps, "runs": summaries}
            )
        )
        return 0
    header = f"{'agent / filter':<22}" + "".join(f"{q + ' median':>18}{'inside':>8}" for q in QUANTITIES)
    print(
        f"{args.env_id}: {len(args.seeds)} runs x {args.steps} steps; values are sums over runs / summed dof"
    )
    print(header)
    for s in summaries:
        cells = "".join(
            f"{s[q]['median'] if s[q]['median'] is not None else float('nan'):>18.2f}{s[q]['inside']:>8.0%}"
            for q in QUANTITIES
        )
        print(f"{s['label']:<22}{cells}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
