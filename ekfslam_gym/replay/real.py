"""A real data set replayed from its path, with the figures every report prints and its picture: what
``ekfslam-replay --dataset gtsam|mrclam`` runs (the command line parses and prints only).

A GTSAM 2-D file whose odometry is one chain (Victoria Park) replays through ``chain``; an MRCLAM robot's drive
through ``mrclam`` (its drive on one clock, the velocity model). ``smoother=True`` adds the full-SLAM smoother on
the same data (``smoother.compare_with_smoother``); the figures then hold ``smoother``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..data.gtsam2d import Gtsam2dDataset
from ..data.mrclam import MRCLAMRun
from .mrclam import ReplaySettings
from .result import Replay
from .smoother import SmootherComparison

__all__ = ["RealDataReplay", "replay_gtsam", "replay_mrclam", "text_report"]


@dataclass(eq=False)  # holds arrays
class RealDataReplay:
    """The replay, its figures (``figures.replay_figures`` / ``figures.summarise``, with ``smoother``), the
    smoother's comparison if asked for, and the survey (ids, xy) the map is judged by, if any."""

    source: Path
    replay: Replay
    figures: dict[str, Any]
    smoother: SmootherComparison | None = None
    survey: tuple[Any, Any] | None = None

    def save_picture(self, path: str | os.PathLike[str]) -> Path:
        """The trajectory and the map (in the survey's frame, when there is one), beside the smoother's."""
        from .pictures import save_map_picture, save_trajectory_picture

        result, smoothed = self.replay, None if self.smoother is None else self.smoother.poses
        if self.survey is None:
            observed = result.ekf.observed
            title = f"{self.source}: {self.figures['variant']}"
            return save_trajectory_picture(
                path, result.poses, result.ekf.landmarks[observed], result.ekf.landmark_covs()[observed],
                smoothed=smoothed, title=title,
            )  # fmt: skip
        from .mrclam import landmark_errors

        _, transform = landmark_errors(result.landmark_estimates(), *self.survey)
        title = f"{self.source}, {self.figures['variant']}, {self.figures['association']} association"
        return save_map_picture(path, result, transform, *self.survey, smoothed, title)


def replay_gtsam(dataset: Gtsam2dDataset, variant: str = "ekf", *, smoother: bool = False) -> RealDataReplay:
    """Replay a GTSAM 2-D data set's odometry chain and readings (``data.gtsam2d.read_gtsam2d``; a file that
    is not one chain fails ``chain.check_chain``)."""
    from .chain import replay_chain
    from .figures import replay_figures
    from .smoother import compare_with_smoother

    result = replay_chain(dataset, variant)
    figures = replay_figures(result, variant)
    comparison = compare_with_smoother(result, dataset) if smoother else None
    if comparison is not None:
        figures["smoother"] = comparison.figures()
    return RealDataReplay(dataset.path, result, figures, comparison)


def replay_mrclam(
    run: MRCLAMRun, settings: ReplaySettings | None = None, *, robots: bool = False, smoother: bool = False
) -> RealDataReplay:
    """Replay an MRCLAM robot's drive (``data.mrclam.load_mrclam``) with ``settings`` (``ReplaySettings()``
    without), with the other robots' barcodes as readings too if ``robots``; the map is judged against the
    survey."""
    from .figures import summarise
    from .mrclam import build_drive, replay_drive
    from .smoother import compare_with_smoother

    settings = ReplaySettings() if settings is None else settings
    survey = (run.landmarks.ids, run.landmarks.positions)
    drive = build_drive(run, robots=robots)
    result = replay_drive(drive, run.landmarks.ids, settings)
    figures = summarise(result, settings, *survey)
    comparison = compare_with_smoother(result, drive, settings=settings, survey=survey) if smoother else None
    if comparison is not None:
        figures["smoother"] = comparison.figures()
    return RealDataReplay(Path(f"MRCLAM robot {run.robot}"), result, figures, comparison, survey)


def text_report(figures: dict[str, Any], source: str | os.PathLike[str]) -> str:
    """The figures of a real data set's replay for reading: one report for every data set, its lines for what
    the figures hold (landmark errors against a survey, association counts, the smoother)."""
    nis = figures["nis"]
    association = f", {figures['association']} association" if "association" in figures else ""
    lines = [
        f"EKF-SLAM ({figures['variant']}{association}) on {source}: {figures['steps']} steps, "
        f"{figures['microseconds_per_step']:.1f} us per step ({figures['seconds']:.2f} s in the filter), "
        f"{figures['landmarks_mapped']} landmarks mapped",
        f"NIS: mean {nis['mean']:.2f} over {nis['readings']} re-observations (2 dof: 2), "
        f"{100 * nis['inside']:.1f} % inside the 95 % band, {100 * nis['windows_inside']:.0f} % of "
        f"{nis['window']}-reading means inside theirs",
    ]
    if "landmark_errors" in figures:
        lines.append(
            f"landmarks after SE(2) alignment to the survey: median {figures['median_error']:.3f} m, "
            f"{figures['within_0.18']} of {figures['landmarks_mapped']} within 0.18 m"
        )
        lines += [f"  {k:>3}: {v:.3f} m" for k, v in figures["landmark_errors"].items()]
    if figures.get("association", "known") != "known":
        lines.append(
            f"associations against the barcodes: {figures['false_associations']} false, "
            f"{figures['missed_associations']} missed, {figures['new_landmarks']} landmarks started"
        )
    if "smoother" in figures:
        s = figures["smoother"]
        dof = f" for {s['dof']} dof" if "dof" in s else ""
        median = f"; landmark median {s['median_error']:.3f} m" if "median_error" in s else ""
        lines.append(
            f"smoother (LM): chi2 {s['chi2']:.1f}{dof}, {s['iterations']} iterations, {s['seconds']:.1f} s; "
            f"trajectory vs filter: {s['trajectory_gap_rms']:.3f} m rms, {s['trajectory_gap_max']:.3f} m max"
            f"{median}"
        )
    return "\n".join(lines)
