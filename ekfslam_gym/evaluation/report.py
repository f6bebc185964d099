"""Reports of an evaluation: JSON-safe values, plain-text and markdown tables, and box plots.

``--format json`` (``--json``) output of the evaluate command: one agent gives ``{"agent": str, "episodes": int, "metrics": {name:
{"iqm": x, "ci": [lo, hi], "mean": x}}}``; several agents (a comparison) an object keyed by agent name whose
values are such objects, in the order the agents were given. NaN is written as ``null``. ``--format blocks`` (the
default) prints ``text_summary`` per agent, ``--format table`` one ``markdown_table``; both take what
``aggregate.summary(name, episodes)`` returns (``aggregate`` alone lacks the name and the episode count).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import metrics
from .episode_metrics import METRIC_KEYS, NEES_STEP_BOUNDS, POSE_DIM

# Which way is better, for the table's arrows (None: neither, e.g. ANEES should be near 3, path length is context).
BETTER: dict[str, str | None] = {
    "smoother_ate": "lower",
    "smoother_landmark_rmse": "lower",
    "return": "higher",
    "map_log_det": "lower",
    "pose_log_det": "lower",
    "landmark_rmse": "lower",
    "missed_landmarks": "lower",
    "seen_fraction": "higher",
    "ate": "lower",
    "anees": None,
    "nees_in_bounds": "higher",
    "loop_closures": "higher",
    "collisions": "lower",
    "path_length": None,
    "belief_truth_pearson": "higher",
    "belief_truth_spearman": "higher",
    "map_nees": None,
    "false_associations": "lower",
    "missed_associations": "lower",
}


def metric_label(key: str) -> str:
    """A metric's name with the way that is better, for a plot's axis or title."""
    better = BETTER.get(key)
    return f"{key} ({better} is better)" if better else key


def json_safe(value: Any) -> Any:
    """NaN and inf are not JSON: write them as null."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value


def format_value(value: float) -> str:
    if value is None or not math.isfinite(value):
        return "n/a"
    magnitude = abs(value)
    if magnitude >= 100:
        return f"{value:.0f}"
    if magnitude >= 10:
        return f"{value:.1f}"
    if magnitude >= 0.1:
        return f"{value:.2f}"
    return f"{value:.3g}"


def _as_summaries(value: Mapping[str, Any]) -> Mapping[str, Mapping[str, Any]]:
    """``{name: summary}`` as it is, one ``summary(...)`` as a table of one row; ``aggregate(...)``'s metrics alone
    (no name, no episode count) refused with the call that works."""
    if "metrics" in value and "agent" in value:  # one summary(name, episodes)
        return {str(value["agent"]): value}
    if value and all(isinstance(v, Mapping) and "iqm" in v for v in value.values()):
        raise TypeError(
            "expected summaries {name: summary(name, episodes)} or one summary(name, episodes), got aggregate()'s "
            "metrics, which lack the name and the episode count: pass summary(name, episodes) instead"
        )
    for name, s in value.items():
        if not (isinstance(s, Mapping) and "metrics" in s and "episodes" in s):
            raise TypeError(f"{name!r} is not a summary(name, episodes) {{'agent', 'episodes', 'metrics'}}")
    return value


def _metric(summary: Mapping[str, Any], name: str, key: str) -> Mapping[str, Any]:
    try:
        return summary["metrics"][key]
    except KeyError:
        raise KeyError(f"{name!r} has no metric {key!r}; it has {sorted(summary['metrics'])}") from None


def markdown_table(summaries: Mapping[str, Mapping[str, Any]], keys: Sequence[str] | None = None) -> str:
    """Agents as rows, metrics as columns, cells ``IQM [lo, hi]``; a note on seeds and NEES bounds below.

    ``summaries`` is ``{name: summary(name, episodes)}`` (``ekfslam_gym.evaluation.aggregate.summary``), or one
    summary for a table of one row. ``keys`` are the columns, by default the first summary's metrics (``METRIC_KEYS``
    for the evaluate command's summaries)."""
    summaries = _as_summaries(summaries)
    if keys is None:
        keys = list(next(iter(summaries.values()))["metrics"]) if summaries else list(METRIC_KEYS)
    arrows = {"higher": "↑", "lower": "↓"}
    header = ["agent", "episodes"] + [f"{k} {arrows.get(BETTER.get(k) or '', '')}".strip() for k in keys]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for name, s in summaries.items():
        cells = [name, str(s["episodes"])]
        for k in keys:
            m = _metric(s, name, k)
            cells.append(f"{format_value(m['iqm'])} [{format_value(m['ci'][0])}, {format_value(m['ci'][1])}]")
        lines.append("| " + " | ".join(cells) + " |")
    n = max((s["episodes"] for s in summaries.values()), default=1)
    lo, hi = metrics.nees_bounds(POSE_DIM, max(n, 1))
    lines.append("")
    lines.append(
        f"IQM over episodes [95 % bootstrap CI]. Pose NEES per-step 95 % bounds [{NEES_STEP_BOUNDS[0]:.3f}, "
        f"{NEES_STEP_BOUNDS[1]:.2f}] (nees_in_bounds should be near 0.95); the mean of {n} independent runs' "
        f"NEES lies in [{lo:.2f}, {hi:.2f}] (chi2 bounds, ANEES ideal 3; the time average within an episode "
        "is correlated, so read anees against these only as a guide)."
    )
    return "\n".join(lines) + "\n"


def text_summary(s: Mapping[str, Any]) -> str:
    """A plain-text block for one agent, ``s = summary(name, episodes)`` (what the CLI prints by default)."""
    summaries = _as_summaries(s)
    if len(summaries) != 1:
        raise TypeError(f"expected one summary(name, episodes), got {len(summaries)}: {list(summaries)}")
    (s,) = summaries.values()
    width = (
        max([len("metric"), *map(len, s["metrics"])]) + 2
    )  # the longest name sets the column, none overflows
    lines = [
        f"{s['agent']}: {s['episodes']} episodes",
        f"  {'metric':<{width}}{'IQM':>10}  {'95% CI':<22}{'mean':>10}",
    ]
    for k, m in s["metrics"].items():
        ci = f"[{format_value(m['ci'][0])}, {format_value(m['ci'][1])}]"
        lines.append(f"  {k:<{width}}{format_value(m['iqm']):>10}  {ci:<22}{format_value(m['mean']):>10}")
    return "\n".join(lines)


def boxes_with_iqm(ax: Any, data: Sequence[np.ndarray], size: float = 1.0) -> np.ndarray:
    """One box per array of episodes on ``ax``, with its IQM and 95 % bootstrap CI drawn over it in red; the
    boxes' x positions (1, 2, ...). ``size`` scales the markers."""
    positions = np.arange(1, len(data) + 1)
    ax.boxplot(data, positions=positions, widths=0.6, showfliers=True, flierprops={"markersize": 3 * size})
    for p, values in zip(positions, data):
        if values.size:
            centre = metrics.iqm(values)
            lo, hi = metrics.bootstrap_ci(values)
            ax.errorbar([p], [centre], yerr=[[centre - lo], [hi - centre]], fmt="o", color="tab:red",
                        markersize=4 * size, capsize=3 * size)  # fmt: skip
    return positions


def plot_results(
    episodes: Mapping[str, Sequence[Mapping[str, float]]], path: str | Path, keys: Sequence[str] = METRIC_KEYS
) -> Path:
    """One box plot per metric (episodes per agent), with the IQM and its CI drawn over each box."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    names = list(episodes)
    cols = 4
    rows = int(math.ceil(len(keys) / cols))
    figure = Figure(figsize=(3.2 * cols, 2.6 * rows), layout="constrained")
    FigureCanvasAgg(figure)
    for i, key in enumerate(keys):
        ax = figure.add_subplot(rows, cols, i + 1)
        data = []
        for name in names:
            values = np.array([e[key] for e in episodes[name]], dtype=float)
            data.append(values[np.isfinite(values)])
        positions = boxes_with_iqm(ax, data)
        ax.set_xticks(positions, names, rotation=30, fontsize=8)
        ax.set_title(metric_label(key), fontsize=9)
        ax.tick_params(axis="y", labelsize=8)
    figure.suptitle("box: episodes; red: IQM with 95 % bootstrap CI", fontsize=9)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    return path
