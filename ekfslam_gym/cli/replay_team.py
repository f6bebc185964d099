"""``ekfslam-replay --dataset mrclam --team``: MRCLAM's five robots through one joint filter, beside the five
single-robot replays (``ekfslam_gym.replay.team``, ``ekfslam_gym.replay.team_report``)."""

from __future__ import annotations

import argparse
import json

from ..evaluation.report import json_safe
from .common import refuse


def replay_team_data(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """Replay every robot alone, then all of them in one filter; print the table (or one JSON object)."""
    from ..data.mrclam import ROBOT_SUBJECTS, load_mrclam
    from ..replay.mrclam import FITTED_MRCLAM, ReplaySettings, build_drive, replay_drive
    from ..replay.team import TeamReplaySettings, replay_team
    from ..replay.team_report import save_team_picture, single_figures, team_figures, team_table

    try:  # the folder the user named: one line naming it, exit 2
        runs = [load_mrclam(args.data, robot) for robot in ROBOT_SUBJECTS]
    except (OSError, ValueError) as error:
        refuse(parser, "--data", error)
    noise = FITTED_MRCLAM if args.noise == "fitted" else ReplaySettings()
    settings = TeamReplaySettings.with_noise_of(noise, variant=args.variant or "ekf")
    alone = noise.choosing(variant=settings.variant)
    singles = [single_figures(replay_drive(build_drive(run), run.landmarks.ids, alone), run) for run in runs]
    result = replay_team(runs, settings)  # anything raised here is not the user's input: a traceback
    joint = team_figures(result)
    if args.plot is not None:
        save_team_picture(
            args.plot,
            result,
            f"MRCLAM, five robots in one filter ({settings.variant}), aligned to the survey",
        )
    if args.json:
        print(json.dumps(json_safe({"single": singles, "team": joint}), allow_nan=False))
        return 0
    print(
        f"EKF-SLAM ({settings.variant}, range sigma {settings.range_std} m, bearing sigma {settings.bearing_std} "
        f"rad) on {args.data}: each robot alone, then the five in one filter ({joint['events']} steps, "
        f"{joint['landmark_nis']['readings']} landmark and {joint['robot_nis']['readings']} robot "
        f"re-observations, {joint['seconds']:.1f} s in the filter)\n"
    )
    print(team_table(singles, [("five robots, one filter", joint)]))
    print("\nlandmark errors after SE(2) alignment to the survey [m]:")
    print("  subject " + " ".join(f"{'robot ' + str(s['robot']):>8}" for s in singles) + "     team")
    for subject, error in joint["landmark_errors"].items():
        cells = " ".join(f"{s['landmark_errors'].get(subject, float('nan')):8.3f}" for s in singles)
        print(f"  {subject:>7} {cells} {error:8.3f}")
    return 0
