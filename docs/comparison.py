"""Draw docs/comparison.png, box plots of the held-out episodes of the baselines and the shipped policies.

    python docs/comparison.py   # from docs/data/heldout_<env-id>.csv

Each CSV holds one row per held-out episode (seeds 10000-10049) and agent, written from the per-episode metrics
of ``ekfslam-evaluate --agent random,circle,lawnmower,greedy,frontier,ppo --model
models/ppo_<env-id>.zip --env-id <env-id> --episodes-json F`` by ``--from-json F``. Landmark RMSE, ATE and ANEES
are drawn on log axes (one circling episode reaches an ANEES in the thousands); the other axes are clipped to
the boxes' whiskers, with the episodes beyond them counted above or below each box. Figures for reporting, never
for tuning.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

DOCS = Path(__file__).resolve().parent
DATA = DOCS / "data"
ENV_IDS = ("EKFSLAM-v0", "EKFSLAM-Loop-v0", "EKFSLAM-Large-v0")
AGENTS = ("random", "circle", "lawnmower", "greedy", "frontier", "ppo")
# (metric, axis title, axis): "log", "linear", or "clip": linear, spanning the whiskers of FOCUS (the agents
# that compete: the planners and the shipped policy; random driving, the blind circle and the lawnmower can sit
# hundreds of nats away)
FOCUS = ("greedy", "frontier", "ppo")
PANELS = (
    ("map_log_det", "map log det (nats) ↓", "clip"),
    ("landmark_rmse", "landmark RMSE (m) ↓", "log"),
    ("seen_fraction", "landmarks seen ↑", "linear"),
    ("ate", "ATE (m) ↓", "log"),
    ("anees", "pose ANEES (3 when consistent)", "log"),
    ("loop_closures", "loop closures ↑", "linear"),
)
COLUMNS = 3


def from_json(path: Path, env_id: str) -> Path:
    """The per-episode metrics of ``evaluate --episodes-json`` as docs/data/heldout_<env-id>.csv."""
    episodes = json.loads(Path(path).read_text())
    out = DATA / f"heldout_{env_id}.csv"
    out.parent.mkdir(parents=True, exist_ok=True)
    keys = ["seed"] + [key for key, _, _ in PANELS]
    with out.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["agent", *keys])
        for name, rows in episodes.items():
            agent = "ppo" if name.startswith("ppo") else name
            for row in rows:
                writer.writerow([agent, *(row[key] for key in keys)])
    return out


def read(env_id: str) -> dict[str, dict[str, np.ndarray]] | None:
    path = DATA / f"heldout_{env_id}.csv"
    if not path.is_file():
        return None
    table: dict[str, dict[str, list[float]]] = {}
    with path.open() as handle:
        for row in csv.DictReader(handle):
            agent = table.setdefault(row["agent"], {})
            for key, value in row.items():
                if key != "agent":
                    agent.setdefault(key, []).append(float(value) if value not in ("", "nan") else np.nan)
    return {agent: {k: np.asarray(v) for k, v in cols.items()} for agent, cols in table.items()}


def _whiskers(values: np.ndarray) -> tuple[float, float]:
    q1, q3 = np.percentile(values, [25, 75])
    reach = 1.5 * (q3 - q1)
    inside = values[(values >= q1 - reach) & (values <= q3 + reach)]
    return float(inside.min()), float(inside.max())


def _clip(ax: Any, positions: np.ndarray, values: list[np.ndarray], focus: list[bool]) -> None:
    """Limit a linear axis to the whiskers of the focus agents; count the episodes beyond it at each box's edge
    (and give the IQM of a box that lies off the axis altogether)."""
    from ekfslam_gym.evaluation import metrics

    ends = [_whiskers(v) for v, f in zip(values, focus) if f and v.size] or [_whiskers(v) for v in values]
    low, high = min(e[0] for e in ends), max(e[1] for e in ends)
    pad = 0.08 * (high - low or 1.0)
    low, high = low - pad, high + pad
    ax.set_ylim(low, high)
    for p, v in zip(positions, values):
        above, below = int((v > high).sum()), int((v < low).sum())
        centre = metrics.iqm(v) if v.size else np.nan
        off = f"\nIQM {centre:.3g}" if not low <= centre <= high else ""
        if above:
            ax.annotate(
                f"{above}↑{off if centre > high else ''}", (p, high), ha="center", va="top", fontsize=6
            )
        if below:
            ax.annotate(
                f"{below}↓{off if centre < low else ''}", (p, low), ha="center", va="bottom", fontsize=6
            )


def draw(path: Path) -> Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ekfslam_gym.evaluation.report import boxes_with_iqm

    envs = [(env_id, data) for env_id in ENV_IDS if (data := read(env_id)) is not None]
    rows = -(-len(PANELS) // COLUMNS)
    figure = Figure(figsize=(3.4 * COLUMNS, 2.6 * rows * len(envs)), layout="constrained")
    FigureCanvasAgg(figure)
    for row, (env_id, data) in enumerate(envs):
        names = [a for a in AGENTS if a in data]
        labels = ["shipped\nPPO" if a == "ppo" else a for a in names]
        for col, (key, title, axis) in enumerate(PANELS):
            ax = figure.add_subplot(rows * len(envs), COLUMNS, row * rows * COLUMNS + col + 1)
            values = [data[a][key][np.isfinite(data[a][key])] for a in names]
            if axis == "log":
                values = [v[v > 0] for v in values]
            positions = boxes_with_iqm(ax, values, size=0.7)
            if axis == "log":
                ax.set_yscale("log")
            elif axis == "clip":
                _clip(ax, positions, values, [n in FOCUS for n in names])
            ax.set_xticks(positions, labels, rotation=30, fontsize=7)
            ax.tick_params(axis="y", labelsize=7)
            ax.set_title(f"{env_id}: {title}", fontsize=8)
    missing = [env_id for env_id in ENV_IDS if env_id not in dict(envs)]
    figure.suptitle(
        "held-out seeds 10000-10049, 50 episodes each; box: episodes (n↑ / n↓: episodes beyond the clipped axis); "
        "red: IQM with its 95 % bootstrap CI"
        + (f"\nnot drawn (no episodes in docs/data): {', '.join(missing)}" if missing else ""),
        fontsize=8,
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=100)
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--from-json", nargs=2, metavar=("EPISODES.json", "ENV_ID"), action="append", default=[],
                        help="first convert an evaluate --episodes-json file into docs/data/")  # fmt: skip
    parser.add_argument("--out", type=Path, default=DOCS / "comparison.png")
    args = parser.parse_args(argv)
    for path, env_id in args.from_json:
        print(f"wrote {from_json(Path(path), env_id)}")
    print(f"wrote {draw(args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
