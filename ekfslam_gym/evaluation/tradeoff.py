"""Where agents sit between two metrics: each model's IQM with its 95 % bootstrap CI on both, the models that no
other model beats on both (the Pareto front), and a scatter plot of them.

Active SLAM trades certainty against accuracy: a policy that reads more landmarks lowers the map's log det and
reads many of them from a drifted pose. A table row per metric hides which side of the trade a model chose; the
two metrics plotted against each other, every model at once, show whether a change moved a model along the
trade or past it. Points come from the per-episode metrics that ``evaluate --episodes-json`` writes, or from a
CSV of points this module wrote, so a figure can be redrawn from a small file once the episodes are gone.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .aggregate import aggregate
from .report import BETTER, metric_label

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["Point", "pareto_front", "points_from_episodes", "read_csv", "tradeoff_figure", "write_csv"]


@dataclass(frozen=True)
class Point:
    """One model (or agent) of a group: IQM and 95 % CI of the x and y metrics over its episodes."""

    group: str
    name: str
    episodes: int
    x: float
    x_lo: float
    x_hi: float
    y: float
    y_lo: float
    y_hi: float


def points_from_episodes(
    episodes: Mapping[str, Sequence[Mapping[str, float]]], x: str, y: str, group: str
) -> list[Point]:
    """One point per name of ``{name: [episode metrics]}`` (the ``--episodes-json`` layout), aggregated as the
    evaluation tables are: IQM and seeded percentile-bootstrap CI, undefined (NaN) episodes left out."""
    points = []
    for name, eps in episodes.items():
        if not eps:
            raise ValueError(f"{group}: {name!r} has no episodes")
        for i, e in enumerate(eps):
            if not isinstance(e, Mapping):
                raise ValueError(f"{group}: episode {i} of {name!r} is not a mapping of metrics")
            for key in (x, y):
                if key not in e:
                    raise ValueError(f"{group}: episode {i} of {name!r} has no {key!r}")
        # evaluate's JSON writes an undefined metric (NaN) as null
        table = aggregate([{k: math.nan if e[k] is None else e[k] for k in (x, y)} for e in eps], (x, y))
        points.append(
            Point(group, name, len(eps), table[x]["iqm"], *table[x]["ci"], table[y]["iqm"], *table[y]["ci"])
        )
    return points


def _orientation(key: str) -> float:
    """+1 where lower is better, -1 where higher is; a metric with no better side has no front."""
    better = BETTER.get(key)
    if better is None:
        raise ValueError(f"{key!r} has no better side, so no model can beat another on it")
    return 1.0 if better == "lower" else -1.0


def pareto_front(points: Iterable[Point], x: str, y: str) -> list[Point]:
    """The points that no other point beats on both metrics (at least as good on both, better on one), in order
    of the x metric from its best end. Points with an undefined IQM are left out; equal points are all kept."""
    sx, sy = _orientation(x), _orientation(y)
    finite = [p for p in points if math.isfinite(p.x) and math.isfinite(p.y)]
    ordered = sorted(finite, key=lambda p: (sx * p.x, sy * p.y))
    front: list[Point] = []
    best_y = math.inf  # the best oriented y among points with a better or equal oriented x
    for p in ordered:
        oy = sy * p.y
        tied = front and front[-1].x == p.x and front[-1].y == p.y
        if oy < best_y or tied:
            front.append(p)
            best_y = min(best_y, oy)
    return front


def write_csv(points: Iterable[Point], path: str | Path, x: str, y: str) -> Path:
    """The points as CSV, headed by the metric names so that :func:`read_csv` knows which metrics they are."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["group", "name", "episodes", x, f"{x}_lo", f"{x}_hi", y, f"{y}_lo", f"{y}_hi"])
        for p in points:
            writer.writerow(
                [p.group, p.name, p.episodes]
                + [repr(float(v)) for v in (p.x, p.x_lo, p.x_hi, p.y, p.y_lo, p.y_hi)]
            )
    return path


def read_csv(path: str | Path) -> tuple[str, str, list[Point]]:
    """The x metric, the y metric and the points of a CSV that :func:`write_csv` wrote."""
    with Path(path).open(newline="") as f:
        rows = list(csv.reader(f))
    if not rows or len(rows[0]) != 9 or rows[0][:3] != ["group", "name", "episodes"]:
        raise ValueError(
            f"{path}: not a CSV of trade-off points (group,name,episodes,x,x_lo,x_hi,y,y_lo,y_hi)"
        )
    x, y = rows[0][3], rows[0][6]
    points = []
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != 9:
            raise ValueError(f"{path}:{line}: expected 9 fields, got {len(row)}")
        points.append(Point(row[0], row[1], int(row[2]), *(float(v) for v in row[3:])))
    return x, y, points


def tradeoff_figure(
    points: Sequence[Point],
    x: str,
    y: str,
    *,
    ci_groups: Sequence[str] = (),
    annotate_groups: Sequence[str] = (),
    x_lines: Sequence[tuple[float, str]] = (),
    y_lines: Sequence[tuple[float, str]] = (),
    front: bool = True,
    title: str | None = None,
) -> Figure:
    """A scatter of the points' IQMs, one colour per group in the order the groups first appear. Groups in
    ``ci_groups`` get their 95 % CIs as error bars and those in ``annotate_groups`` their names; ``x_lines`` and
    ``y_lines`` are labelled reference lines (a baseline's CI end, say); ``front`` draws the Pareto front of all
    the points as a dashed staircase. The figure has an Agg canvas and never touches pyplot."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(7.5, 5.2), layout="constrained")
    FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    groups = list(dict.fromkeys(p.group for p in points))
    markers = "os^Dv<>Ph*"
    for i, group in enumerate(groups):
        members = [p for p in points if p.group == group and math.isfinite(p.x) and math.isfinite(p.y)]
        colour = f"C{i % 10}"
        xs = np.array([p.x for p in members])
        ys = np.array([p.y for p in members])
        if group in ci_groups:
            # a percentile interval can miss its IQM by a hair; matplotlib refuses negative bar lengths
            ax.errorbar(
                xs, ys,
                xerr=np.maximum(0.0, [xs - [p.x_lo for p in members], [p.x_hi for p in members] - xs]),
                yerr=np.maximum(0.0, [ys - [p.y_lo for p in members], [p.y_hi for p in members] - ys]),
                fmt="none", ecolor=colour, alpha=0.5, capsize=2, linewidth=0.8,
            )  # fmt: skip
        many = len(members) > 30
        ax.scatter(xs, ys, s=10 if many else 30, alpha=0.45 if many else 0.9, color=colour,
                   marker=markers[i % len(markers)], label=f"{group} ({len(members)})", zorder=3)  # fmt: skip
        if group in annotate_groups:
            for p in members:
                ax.annotate(p.name, (p.x, p.y), xytext=(4, 3), textcoords="offset points", fontsize=7)
    if front:
        staircase = pareto_front(points, x, y)
        if staircase:
            ax.plot([p.x for p in staircase], [p.y for p in staircase], drawstyle="steps-post", color="0.3",
                    linestyle="--", linewidth=1, label="Pareto front of all points", zorder=2)  # fmt: skip
    for value, text in x_lines:
        ax.axvline(value, color="0.5", linestyle=":", linewidth=1)
        ax.annotate(text, (value, 1), xycoords=("data", "axes fraction"), xytext=(3, -3),
                    textcoords="offset points", rotation=90, va="top", fontsize=7, color="0.35")  # fmt: skip
    for value, text in y_lines:
        ax.axhline(value, color="0.5", linestyle=":", linewidth=1)
        ax.annotate(text, (1, value), xycoords=("axes fraction", "data"), xytext=(-3, 3),
                    textcoords="offset points", ha="right", fontsize=7, color="0.35")  # fmt: skip
    ax.set_xlabel(metric_label(x))
    ax.set_ylabel(metric_label(y))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    ax.set_title(title or "IQM over each model's episodes", fontsize=9, wrap=True)
    return figure
