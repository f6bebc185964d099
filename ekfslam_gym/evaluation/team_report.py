"""Figures, table and picture of a cooperative MRCLAM replay (``team_replay``) beside the single-robot ones.

The map of each filter is judged against the survey after its own best SE(2) alignment (``mrclam.landmark_errors``);
NIS (2 dof, ``real_data.nis_summary``) of landmark and robot readings apart, and per observing robot.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ..data.mrclam import MRCLAMRun
from .mrclam import RealReplay
from .real_data import nis_summary, summarise
from .team_replay import TeamReplay

__all__ = ["save_team_picture", "single_figures", "team_figures", "team_table"]

WITHIN = 0.18  # m: the yardstick of the single-robot page


def _map_figures(errors: dict[int, float]) -> dict[str, Any]:
    values = np.array(list(errors.values()))
    return {
        "landmark_errors": {str(k): v for k, v in sorted(errors.items())},
        "median_error": float(np.median(values)) if len(values) else None,
        "within_0.18": int(np.sum(values <= WITHIN)),
        "landmarks_mapped": len(values),
    }


def single_figures(result: RealReplay, run: MRCLAMRun) -> dict[str, Any]:
    """A single-robot replay's figures (``real_data.summarise`` against ``run``'s survey) with its robot."""
    return {"robot": run.robot, **summarise(result, run.landmarks.ids, run.landmarks.positions)}


def team_figures(result: TeamReplay) -> dict[str, Any]:
    """The joint replay's figures: the team's landmark errors after alignment, NIS of landmark and robot
    readings (all, and per observing robot), the robots' starts, the filter's time."""
    errors, transform = result.landmark_errors()
    per_robot = []
    for k, run in enumerate(result.runs):
        per_robot.append(
            {
                "robot": run.robot,
                "landmark_nis": nis_summary(result.landmark_nis[result.landmark_observer == k]),
                "robot_nis": nis_summary(result.robot_nis[result.robot_observer == k]),
                "start": result.starts[k].tolist(),
            }
        )
    replay = result.settings.replay
    return {
        "robots": [run.robot for run in result.runs],
        "variant": replay.variant,
        "range_std": replay.range_std,
        "bearing_std": replay.bearing_std,
        "robot_readings": result.settings.robot_readings,
        "events": result.events,
        **_map_figures(errors),
        "landmark_nis": nis_summary(result.landmark_nis),
        "robot_nis": nis_summary(result.robot_nis),
        "per_robot": per_robot,
        "seconds": result.seconds,
        "microseconds_per_step": 1e6 * result.seconds / max(result.events, 1),
        "alignment": {"angle": transform.angle, "translation": transform.translation.tolist()},
    }


def team_table(singles: list[dict[str, Any]], joint: list[tuple[str, dict[str, Any]]]) -> str:
    """A Markdown table: one row per single-robot replay (``summarise``'s figures with ``robot``), then one
    per joint replay (name, ``team_figures``)."""
    lines = [
        "| filter | landmarks mapped | median error [m] | within 0.18 m | landmark NIS (mean, inside 95 %) | "
        "robot NIS (mean, inside 95 %) |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for figures in singles:
        nis = figures["nis"]
        lines.append(
            f"| robot {figures['robot']} alone | {figures['landmarks_mapped']} | {figures['median_error']:.3f} | "
            f"{figures['within_0.18']} / {figures['landmarks_mapped']} | {nis['mean']:.2f}, "
            f"{100 * nis['inside']:.0f} % | - |"
        )
    for name, figures in joint:
        lm, rr = figures["landmark_nis"], figures["robot_nis"]
        robot_cell = f"{rr['mean']:.2f}, {100 * rr['inside']:.0f} %" if rr["readings"] else "-"
        lines.append(
            f"| {name} | {figures['landmarks_mapped']} | {figures['median_error']:.3f} | "
            f"{figures['within_0.18']} / {figures['landmarks_mapped']} | {lm['mean']:.2f}, "
            f"{100 * lm['inside']:.0f} % | {robot_cell} |"
        )
    return "\n".join(lines)


def save_team_picture(path: str | os.PathLike[str], result: TeamReplay, title: str = "") -> Path:
    """The robots' trajectories and the team's map (3-sigma ellipses, labelled by subject), moved onto the
    survey by the map's best alignment, with the surveyed landmarks."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon

    from ..ellipses import ellipse_points

    _, transform = result.landmark_errors()
    team = result.team
    landmarks = result.runs[0].landmarks
    figure = Figure(figsize=(6.4, 7.6), dpi=110)
    FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    colours = ["tab:red", "tab:orange", "tab:green", "tab:purple", "tab:brown"]
    for k, (run, path_k) in enumerate(zip(result.runs, result.paths, strict=True)):
        moved = transform.poses(path_k)
        colour = colours[k % len(colours)]
        ax.plot(*moved[:, :2].T, color=colour, lw=0.5, alpha=0.75, label=f"robot {run.robot}")
        ax.plot(*moved[0, :2], "o", color=colour, ms=5, mec="k", mew=0.5)
    ax.plot(*landmarks.positions.T, "k+", ms=10, mew=2, label="surveyed landmarks")
    for i, xy in zip(landmarks.ids, landmarks.positions, strict=True):
        ax.annotate(str(int(i)), xy, xytext=(5, -9), textcoords="offset points", fontsize=7)
    seen = np.flatnonzero(team.observed)
    points = transform.points(team.landmarks[seen])
    covs = transform.covariances(team.landmark_covs()[seen])
    ax.plot(*points.T, "o", color="tab:blue", ms=3, label="team's landmarks (3 sigma)")
    for slot, centre, cov in zip(seen, points, covs, strict=True):
        outline, valid = ellipse_points(centre, cov, n=48)
        if valid[0]:
            ax.add_patch(Polygon(outline[0], closed=True, fill=False, color="tab:blue", lw=0.8))
        ax.annotate(
            str(int(landmarks.ids[slot])), centre, xytext=(-12, 4), textcoords="offset points", fontsize=7,
            color="tab:blue",
        )  # fmt: skip
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(title, fontsize=9)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=4, fontsize=7, frameon=False)
    figure.subplots_adjust(left=0.12, right=0.97, bottom=0.14, top=0.95)
    path = Path(path)
    figure.savefig(path, format="png")
    return path
