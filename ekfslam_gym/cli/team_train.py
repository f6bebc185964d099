"""Shared-parameter PPO for a team of robots from a recipe (``ekfslam_gym.multi.training``): one policy, every
robot an independent sample; resumes from the run folder's newest checkpoint.

    python -m ekfslam_gym.cli.team_train configs/multi/ppo_team.yaml runs/team3 --max-minutes 35
"""

from __future__ import annotations

import argparse

from .common import command_line


@command_line("team-train", prog="python -m ekfslam_gym.cli.team_train")
def main(argv: list[str] | None = None) -> None:
    from ..multi.training import read_recipe, train

    parser = argparse.ArgumentParser(
        prog="python -m ekfslam_gym.cli.team_train", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("recipe", help="the recipe YAML (configs/multi/ppo_team.yaml)")
    parser.add_argument("out", help="the run's folder (resumed from its newest checkpoint if it has one)")
    parser.add_argument("--max-minutes", type=float, default=None, help="stop (saved) after this wall time")
    args = parser.parse_args(argv)
    train(read_recipe(args.recipe), args.out, args.max_minutes)


if __name__ == "__main__":
    main()
