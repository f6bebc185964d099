"""Pictures of an EKF-SLAM belief in the style of the Freiburg *Robot Mapping* course's EKF-SLAM figure, and of a
solved pose graph.

True landmarks as black crosses, estimated landmarks with their 3-sigma ellipses in blue, the robot estimate
with its 3-sigma position ellipse and heading in red, the true pose and trajectory in green when known, and
the step's readings as lines from the estimated robot. Rendering only reads the state it is given and
decides nothing.

matplotlib and imageio (the ``render`` extra) are imported lazily, so the package imports without them.
Figures are ``matplotlib.figure.Figure`` objects with an Agg canvas attached: pyplot is never touched, so no
global figure state leaks into the caller's session.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..ellipses import ellipse_points

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ekfslam_gym.data.course import LandmarkMap
    from ekfslam_gym.graph.optimizer import OptimizationResult, Values

__all__ = [
    "Belief",
    "Frame",
    "belief_figure",
    "draw_frame",
    "draw_graph_solution",
    "plot_graph_solution",
    "plot_limits",
    "save_gif",
    "save_png",
]

HEADING_LENGTH = 0.6  # [m] length of the heading tick


@dataclass(frozen=True)
class Belief:
    """The parts of a filter state that are drawn (a copy, so frames can be kept for an animation)."""

    pose: np.ndarray  # (3,) x [m], y [m], heading [rad]
    pose_cov: np.ndarray  # (3, 3)
    landmarks: np.ndarray  # (n, 2)
    landmark_covs: np.ndarray  # (n, 2, 2)
    observed: np.ndarray  # (n,) bool: only these are drawn
    labels: np.ndarray | None = None  # (n,) landmark ids to print next to the estimates

    @classmethod
    def from_state(
        cls,
        mean: np.ndarray,
        cov: np.ndarray,
        observed: np.ndarray | None = None,
        labels: Sequence[int] | np.ndarray | None = None,
    ) -> Belief:
        """Build from a state (x, y, theta, m1x, m1y, ...) and its covariance."""
        mean = np.asarray(mean, dtype=float)
        cov = np.asarray(cov, dtype=float)
        n = (len(mean) - 3) // 2
        slots = 3 + 2 * np.arange(n)
        landmark_covs = np.empty((n, 2, 2))
        for k in range(2):
            for j in range(2):
                landmark_covs[:, k, j] = cov[slots + k, slots + j]
        return cls(
            pose=mean[:3].copy(),
            pose_cov=cov[:3, :3].copy(),
            landmarks=mean[3:].reshape(n, 2).copy(),
            landmark_covs=landmark_covs,
            observed=np.ones(n, bool) if observed is None else np.asarray(observed, bool).copy(),
            labels=None if labels is None else np.asarray(labels).copy(),
        )


@dataclass(frozen=True)
class Frame:
    """Everything drawn at one time step."""

    belief: Belief
    step: int | None = None  # shown in the title as "t = step"
    readings: np.ndarray | None = None  # (m, 2) range [m], bearing [rad], drawn from the estimated pose
    true_pose: np.ndarray | None = None  # (3,)
    true_path: np.ndarray | None = None  # (k, >=2) true trajectory so far
    est_path: np.ndarray | None = None  # (k, >=2) estimated trajectory so far


def _ellipse(ax: Axes, centre: np.ndarray, cov: np.ndarray, color: str, **kwargs: object) -> None:
    from matplotlib.patches import Polygon

    points, valid = ellipse_points(centre, cov, n=64)
    if valid[0]:
        ax.add_patch(Polygon(points[0], closed=True, fill=False, color=color, **kwargs))


def plot_limits(
    frames: Sequence[Frame], world: LandmarkMap | None = None, margin: float = 1.5
) -> tuple[float, ...]:
    """Square (xmin, xmax, ymin, ymax) covering the frames' content, fixed so an animation does not jump."""
    points = [np.zeros((0, 2))]
    if world is not None:
        points.append(world.positions)
    for frame in frames:
        belief = frame.belief
        points.append(belief.pose[None, :2])
        points.append(belief.landmarks[belief.observed])
        for path in (
            frame.true_path,
            frame.est_path,
            None if frame.true_pose is None else frame.true_pose[None],
        ):
            if path is not None and len(path):
                points.append(np.asarray(path)[:, :2])
    xy = np.concatenate(points)
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if not len(xy):
        return (-5.0, 5.0, -5.0, 5.0)
    low, high = xy.min(axis=0) - margin, xy.max(axis=0) + margin
    centre, half = (low + high) / 2.0, max(high - low) / 2.0
    return (centre[0] - half, centre[0] + half, centre[1] - half, centre[1] + half)


def draw_frame(
    ax: Axes, frame: Frame, world: LandmarkMap | None = None, limits: Sequence[float] | None = None
) -> None:
    """Draw one frame onto ``ax``."""
    belief = frame.belief
    x, y, theta = belief.pose
    if world is not None and len(world):
        ax.plot(*world.positions.T, "k+", markersize=10, markeredgewidth=2, label="true landmarks", zorder=3)
    if frame.true_path is not None and len(frame.true_path):
        ax.plot(*np.asarray(frame.true_path)[:, :2].T, color="tab:green", lw=1, alpha=0.6, label="true path")
    if frame.est_path is not None and len(frame.est_path):
        ax.plot(
            *np.asarray(frame.est_path)[:, :2].T, color="tab:red", lw=1, ls="--", alpha=0.6, label="estimate"
        )
    if frame.readings is not None and len(frame.readings):
        r, phi = np.asarray(frame.readings, dtype=float).T
        ends = np.column_stack([x + r * np.cos(theta + phi), y + r * np.sin(theta + phi)])
        segments = np.full((len(ends), 3, 2), np.nan)  # robot -> end, then a NaN gap: one artist for all
        segments[:, 0] = (x, y)
        segments[:, 1] = ends
        ax.plot(*segments.reshape(-1, 2).T, color="0.3", lw=0.8, zorder=1, label="readings")
    seen = np.flatnonzero(belief.observed)
    if len(seen):
        ax.plot(*belief.landmarks[seen].T, "o", color="tab:blue", markersize=4, label="landmark estimates")
    for i in seen:
        _ellipse(ax, belief.landmarks[i], belief.landmark_covs[i], "tab:blue", lw=1)
        if belief.labels is not None:
            ax.annotate(
                str(belief.labels[i]),
                belief.landmarks[i],
                xytext=(4, 4),
                textcoords="offset points",
                fontsize=7,
                color="tab:blue",
            )
    if frame.true_pose is not None:
        tx, ty, tt = frame.true_pose
        ax.plot(
            [tx, tx + HEADING_LENGTH * np.cos(tt)], [ty, ty + HEADING_LENGTH * np.sin(tt)], color="tab:green"
        )
        ax.plot([tx], [ty], "o", color="tab:green", markersize=6, label="true pose")
    _ellipse(ax, belief.pose[:2], belief.pose_cov[:2, :2], "tab:red", lw=1.5)
    ax.plot(
        [x, x + HEADING_LENGTH * np.cos(theta)],
        [y, y + HEADING_LENGTH * np.sin(theta)],
        color="tab:red",
        lw=2,
    )
    ax.plot([x], [y], "o", color="tab:red", markersize=6, label="robot estimate")

    if limits is None:
        limits = plot_limits([frame], world)
    ax.set_xlim(limits[0], limits[1])
    ax.set_ylim(limits[2], limits[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    if frame.step is not None:
        ax.set_title(f"t = {frame.step}")
    # below the axes, so it never hides a landmark
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=4, fontsize=7, frameon=False)


def belief_figure(
    frame: Frame, world: LandmarkMap | None = None, limits: Sequence[float] | None = None, dpi: float = 100.0
) -> Figure:
    """A new 6 x 6.6 inch figure (Agg canvas, not registered with pyplot) showing one frame."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(6.0, 6.6), dpi=dpi)
    # fixed margins rather than tight layout: half the drawing time, and every frame the same
    figure.subplots_adjust(left=0.12, right=0.97, bottom=0.17, top=0.95)
    FigureCanvasAgg(figure)
    draw_frame(figure.add_subplot(), frame, world, limits)
    return figure


def save_png(path: str | os.PathLike[str], frame: Frame, world: LandmarkMap | None = None) -> Path:
    """Draw one frame to a PNG file."""
    path = Path(path)
    belief_figure(frame, world).savefig(path, format="png")
    return path


def save_gif(
    path: str | os.PathLike[str],
    frames: Sequence[Frame],
    world: LandmarkMap | None = None,
    fps: float = 10.0,
    dpi: float = 72.0,
) -> Path:
    """Draw frames to an animated GIF (fixed axis limits across frames, lower dpi than the PNG; loops)."""
    import imageio.v3 as iio

    if not frames:
        raise ValueError("no frames to draw")
    limits = plot_limits(frames, world)
    images = []
    for frame in frames:
        figure = belief_figure(frame, world, limits, dpi=dpi)
        figure.canvas.draw()
        images.append(np.asarray(figure.canvas.buffer_rgba())[..., :3].copy())
    path = Path(path)
    iio.imwrite(path, np.stack(images), extension=".gif", duration=1000.0 / fps, loop=0)
    return path


def plot_graph_solution(
    path: str | os.PathLike[str], initial: Values, result: OptimizationResult, title: str = ""
) -> None:
    """Save a PNG of the initial guess and the optimised poses and landmarks (matplotlib, Agg canvas)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 7), dpi=120)
    FigureCanvasAgg(fig)
    draw_graph_solution(fig.add_subplot(), initial, result, title)
    fig.savefig(path)


def draw_graph_solution(ax: Axes, initial: Values, result: OptimizationResult, title: str = "") -> None:
    """Draw the initial guess and the optimised poses and landmarks on a matplotlib axes."""
    ax.plot(initial.poses[:, 0], initial.poses[:, 1], color="0.7", lw=0.8, label="initial poses")
    poses, landmarks = result.values.poses, result.values.landmarks
    ax.plot(poses[:, 0], poses[:, 1], color="tab:blue", lw=0.9, label="optimised poses")
    if len(landmarks):
        ax.scatter(
            landmarks[:, 0], landmarks[:, 1], s=6, color="tab:red", label="optimised landmarks", zorder=3
        )
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(
        f"{title}  F: {result.initial_error:.6g} → {result.final_error:.6g} ({result.iterations} it.)"
    )
    ax.legend(loc="best", fontsize="small")
