"""Draw the picture and print the tables of docs/real-data.md's five-robot section (MRCLAM, cooperative SLAM).

    python docs/real_data_team.py [--data ../shared/data/mrclam]

Writes docs/real_data_mrclam_team.png and prints the Markdown tables: each robot alone and the five in one
filter (with and without the robot-to-robot readings), textbook and fitted noise; each landmark's error; NIS
per observing robot. About a minute and a half on two shared cores.
"""

from __future__ import annotations

import argparse
import platform
from pathlib import Path

import numpy as np

from ekfslam_gym.data.mrclam import ROBOT_SUBJECTS, load_mrclam
from ekfslam_gym.evaluation.mrclam import FITTED_MRCLAM, ReplaySettings, build_drive, replay_drive
from ekfslam_gym.evaluation.team_replay import TeamReplaySettings, replay_team
from ekfslam_gym.evaluation.team_report import save_team_picture, single_figures, team_figures, team_table

DOCS = Path(__file__).resolve().parent


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--data", type=Path, default=DOCS.parents[1] / "shared" / "data" / "mrclam")
    args = parser.parse_args()
    runs = [load_mrclam(args.data, robot) for robot in ROBOT_SUBJECTS]
    print(f"machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}\n")

    results = {}
    for noise_name, noise in (("textbook", ReplaySettings()), ("fitted", FITTED_MRCLAM)):
        singles = [
            single_figures(replay_drive(build_drive(run), run.landmarks.ids, noise), run) for run in runs
        ]
        joint = []
        for name, robot_readings in (
            ("five robots, one filter", True),
            ("five robots, no robot readings", False),
        ):
            result = replay_team(runs, TeamReplaySettings(replay=noise, robot_readings=robot_readings))
            results[noise_name, robot_readings] = (result, team_figures(result))
            joint.append((name, results[noise_name, robot_readings][1]))
        print(f"{noise_name} noise\n")
        print(team_table(singles, joint))
        if noise_name == "textbook":
            base_singles = singles
        print()

    base, figures = results["textbook", True]
    alone = results["textbook", False][1]
    print(
        "| landmark (subject) | "
        + " | ".join(f"robot {r} alone" for r in ROBOT_SUBJECTS)
        + " | team | team, no robot readings |"
    )
    print("|---:|" + "---:|" * (len(ROBOT_SUBJECTS) + 2))
    for subject, error in figures["landmark_errors"].items():
        cells = " | ".join(f"{s['landmark_errors'][subject]:.3f}" for s in base_singles)
        print(f"| {subject} | {cells} | {error:.3f} | {alone['landmark_errors'][subject]:.3f} |")
    values = np.array([v for k, v in figures["landmark_errors"].items() if v < 1.0])
    print(
        f"\nteam, textbook noise, the swapped pair aside: largest {values.max():.3f} m, mean {values.mean():.3f} m"
    )

    print(
        "\n| robot | start x [m] | start y [m] | start heading [rad] | landmark NIS (mean, inside 95 %) | robot NIS (mean, inside 95 %) |"
    )
    print("|---:|---:|---:|---:|---:|---:|")
    for row in figures["per_robot"]:
        lm, rr = row["landmark_nis"], row["robot_nis"]
        x, y, heading = row["start"]
        print(
            f"| {row['robot']} | {x:.2f} | {y:.2f} | {heading:.2f} | {lm['mean']:.2f}, {100 * lm['inside']:.0f} % | "
            f"{rr['mean']:.2f}, {100 * rr['inside']:.0f} % |"
        )
    print(
        f"\nteam filter: {figures['events']} steps, {figures['seconds']:.1f} s, "
        f"{figures['microseconds_per_step']:.0f} us per step (predictions and corrections)"
    )
    picture = save_team_picture(
        DOCS / "real_data_mrclam_team.png", base,
        "MRCLAM: five robots in one EKF (textbook noise, known barcodes), aligned to the survey",
    )  # fmt: skip
    print(f"\nwrote {picture}")


if __name__ == "__main__":
    main()
