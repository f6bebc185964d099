"""The pictures of a replay on real data: the trajectory and map (3-sigma ellipses) in the survey's frame, and
NIS over time against its band. Needs matplotlib (the ``render`` extra)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..evaluation.alignment import SE2Transform
from .figures import nis_band
from .result import Replay

__all__ = ["save_map_picture", "save_nis_picture", "save_trajectory_picture"]


def save_map_picture(
    path: str | os.PathLike[str],
    result: Replay,
    transform: SE2Transform,
    truth_ids: np.ndarray,
    truth_xy: np.ndarray,
    smoothed: np.ndarray | None = None,
    title: str = "",
) -> Path:
    """The filter's trajectory and map (3-sigma ellipses, labelled by barcode subject), moved onto the survey,
    with the surveyed landmarks and, if given, the smoother's trajectory (in the filter's frame)."""
    slots = np.flatnonzero(result.ekf.observed & (result.labels > 0))
    return save_trajectory_picture(
        path,
        transform.poses(result.poses),
        transform.points(result.ekf.landmarks[slots]),
        transform.covariances(result.ekf.landmark_covs()[slots]),
        labels=result.labels[slots],
        truth=(truth_ids, truth_xy),
        smoothed=None if smoothed is None else transform.poses(smoothed),
        title=title,
    )


def save_trajectory_picture(
    path: str | os.PathLike[str],
    poses: np.ndarray,
    landmarks: np.ndarray,
    landmark_covs: np.ndarray,
    *,
    labels: np.ndarray | None = None,
    truth: tuple[np.ndarray, np.ndarray] | None = None,
    smoothed: np.ndarray | None = None,
    title: str = "",
    size: tuple[float, float] = (5.2, 7.0),
) -> Path:
    """A filter's trajectory (n, 3) and landmarks (m, 2) with 3-sigma ellipses (m, 2, 2); optionally their
    labels, the surveyed landmarks (ids, (k, 2)) and a smoother's trajectory, all in one frame."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon

    from ..ellipses import ellipse_points

    figure = Figure(figsize=size, dpi=110)
    FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    ax.plot(*poses[:, :2].T, color="tab:red", lw=0.6, alpha=0.7, label="filter trajectory")
    if smoothed is not None:
        ax.plot(*smoothed[:, :2].T, color="tab:green", lw=0.6, alpha=0.7, label="smoother")
    if truth is not None:
        ax.plot(*np.asarray(truth[1]).T, "k+", ms=10, mew=2, label="surveyed landmarks")
        for i, xy in zip(*truth, strict=True):
            ax.annotate(str(int(i)), xy, xytext=(5, -9), textcoords="offset points", fontsize=7)
    ax.plot(
        *landmarks.T,
        "o",
        color="tab:blue",
        ms=3 if len(landmarks) < 50 else 1.5,
        label="filter landmarks (3 sigma)",
    )
    for centre, cov in zip(landmarks, landmark_covs, strict=True):
        points, valid = ellipse_points(centre, cov, n=48)
        if valid[0]:
            ax.add_patch(Polygon(points[0], closed=True, fill=False, color="tab:blue", lw=0.8))
    if labels is not None:  # by barcode: shows a swapped pair
        for label, xy in zip(labels, landmarks, strict=True):
            ax.annotate(
                str(int(label)), xy, xytext=(-12, 4), textcoords="offset points", fontsize=7, color="tab:blue"
            )
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(title, fontsize=9)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=2, fontsize=7, frameon=False)
    figure.subplots_adjust(left=0.14, right=0.97, bottom=0.16, top=0.95)
    path = Path(path)
    figure.savefig(path, format="png")
    return path


def save_nis_picture(
    path: str | os.PathLike[str],
    runs: dict[str, tuple[np.ndarray, np.ndarray]],
    window: int = 50,
    title: str = "",
    xlabel: str = "time [min]",
) -> Path:
    """Each run's NIS ``{label: (times, nis)}`` as means of ``window`` consecutive re-observations, against
    the band."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(7.0, 3.4), dpi=110)
    FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    lo, hi = nis_band(window)
    for label, (times, nis) in runs.items():
        n = len(nis) // window * window
        means = nis[:n].reshape(-1, window).mean(axis=1)
        ax.plot(np.asarray(times)[:n].reshape(-1, window).mean(axis=1), means, lw=1.0, label=label)
    ax.axhspan(lo, hi, color="0.85", label=f"95 % band of a {window}-reading mean")
    ax.axhline(2.0, color="k", lw=0.6, ls=":")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(f"NIS, mean of {window} readings")
    ax.set_yscale("log")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, loc="lower right", ncol=2)
    figure.subplots_adjust(left=0.11, right=0.98, bottom=0.15, top=0.9)
    path = Path(path)
    figure.savefig(path, format="png")
    return path
