"""Team episodes of one agent on a seed suite, their metrics and their IQM with a 95 % bootstrap CI
(``ekfslam_gym.multi.evaluation``).

    python -m ekfslam_gym.cli.team_evaluate coordinated --robots 3 --seeds heldout --out runs/coordinated3.json
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from .common import command_line


@command_line("team-evaluate", prog="python -m ekfslam_gym.cli.team_evaluate")
def main(argv: list[str] | None = None) -> None:
    from .. import seeds as seed_policy
    from ..multi.evaluation import TEAM_METRICS, evaluate, make_agent, summarise

    parser = argparse.ArgumentParser(
        prog="python -m ekfslam_gym.cli.team_evaluate", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("agent", help="random | independent | coordinated | ppo")
    parser.add_argument("--model", default=None, help="the team policy's zip (agent ppo)")
    parser.add_argument("--robots", type=int, default=3)
    parser.add_argument(
        "--seeds", default="heldout", help="a suite (heldout, eval) or ranges, e.g. 10000-10009"
    )
    parser.add_argument("--out", required=True, help="JSON file of the episodes and their summary")
    args = parser.parse_args(argv)
    seeds = seed_policy.parse_seeds(args.seeds)
    episodes = evaluate(make_agent(args.agent, args.model), args.robots, seeds)
    summary = summarise(episodes)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(
        json.dumps(
            {"agent": args.agent, "robots": args.robots, "episodes": episodes, "summary": summary}, indent=1
        )
    )
    for key in TEAM_METRICS:
        s = summary[key]
        print(f"{key:20s} IQM {s['iqm']:9.3f}  [{s['ci'][0]:.3f}, {s['ci'][1]:.3f}]  mean {s['mean']:.3f}")
    if any(math.isnan(e["map_rmse"]) for e in episodes):
        print("(episodes without a mapped landmark left out of map_rmse)")


if __name__ == "__main__":
    main()
