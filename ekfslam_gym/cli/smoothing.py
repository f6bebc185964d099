"""Filter vs the full-SLAM smoother on env episodes (see ``ekfslam_gym.evaluation.smoothing``).

ekfslam-smoothing [--env-id EKFSLAM-v0] [--seeds 20000-20004] [--agent circle] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys

from ..seeds import EVAL_SEEDS, span
from .common import agent_from_flags, check_env_flags, command_line, command_parser, parse_seeds


@command_line("smoothing")
def main(argv: list[str] | None = None) -> int:
    parser = command_parser(
        "smoothing", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env-id", default="EKFSLAM-v0", help="the registered env to drive")
    parser.add_argument("--agent", default="circle", help="the agent that drives every episode")
    parser.add_argument("--seeds", default=span(EVAL_SEEDS[:5]), type=parse_seeds,
                        help="evaluation seeds by default; A-B, A,B,C or a suite's name (heldout, eval)")  # fmt: skip
    parser.add_argument("--json", action="store_true", help="print one JSON list of the per-seed rows")
    args = parser.parse_args(argv)
    import gymnasium as gym

    from ..evaluation.rollout import run_episode
    from ..evaluation.smoothing import EpisodeRecorder, compare_with_smoother

    check_env_flags(parser, args.env_id)
    rows = []
    for seed in args.seeds:
        env = gym.make(args.env_id)
        recorder = EpisodeRecorder()
        run_episode(env, agent_from_flags(parser, args.agent, {}), seed, recording=recorder)
        rows.append({"seed": seed, **compare_with_smoother(recorder, env)})
    if args.json:
        print(json.dumps(rows))
        return 0
    print(
        f"{'seed':>6} {'steps':>5} | {'filter ATE':>10} {'smoother':>9} | {'filter lm RMSE':>14} {'smoother':>9}"
    )
    for r in rows:
        print(f"{r['seed']:>6} {r['steps']:>5} | {r['filter_ate']:>10.4f} {r['smoother_ate']:>9.4f} | "
              f"{r['filter_landmark_rmse']:>14.4f} {r['smoother_landmark_rmse']:>9.4f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
