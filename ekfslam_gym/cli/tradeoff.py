"""Plot two metrics against each other for many models at once, and list the ones no other model beats on both
(see ``ekfslam_gym.evaluation.tradeoff``).

ekfslam-tradeoff runs/a.json runs/b.json --label "PPO seeds" --label planners --plot out.png

Each FILE is either the per-episode metrics that ``evaluate --episodes-json`` writes ({name: [episodes]}), one
group of points named by its --label (in order) or by the file's stem, or a CSV of points this command wrote
with --csv, whose groups it keeps.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..evaluation.report import BETTER
from ..evaluation.tradeoff import (
    Point,
    pareto_front,
    points_from_episodes,
    read_csv,
    tradeoff_figure,
    write_csv,
)
from .common import command_line, command_parser


def _reference_line(text: str) -> tuple[float, str]:
    value, _, label = text.partition(":")
    try:
        return float(value), label
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected VALUE or VALUE:TEXT, got {text!r}") from None


def _is_csv(path: Path) -> bool:
    return path.suffix.lower() == ".csv"


def _load(path: Path, label: str | None, x: str, y: str) -> list[Point]:
    if _is_csv(path):
        file_x, file_y, points = read_csv(path)
        if (file_x, file_y) != (x, y):
            raise ValueError(f"{path} holds {file_x} against {file_y}, not {x} against {y}")
        return points
    episodes = json.loads(path.read_text())
    if not isinstance(episodes, dict) or not all(isinstance(v, list) for v in episodes.values()):
        raise ValueError(f"{path}: expected {{name: [episode metrics]}} as evaluate --episodes-json writes")
    return points_from_episodes(episodes, x, y, label if label is not None else path.stem)


@command_line("tradeoff")
def main(argv: list[str] | None = None) -> int:
    parser = command_parser(
        "tradeoff", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    metric_names = sorted(BETTER)
    parser.add_argument("files", nargs="+", type=Path, metavar="FILE",
                        help="evaluate --episodes-json files, or CSVs this command wrote")  # fmt: skip
    parser.add_argument(
        "--label", action="append", default=[], help="a group's name, one per JSON file, in order"
    )
    metric_help = "a metric of the episodes, one of " + ", ".join(metric_names) + " (default %(default)s)"
    parser.add_argument(
        "--x", default="map_log_det", choices=metric_names, metavar="METRIC", help=metric_help
    )
    parser.add_argument(
        "--y", default="landmark_rmse", choices=metric_names, metavar="METRIC", help=metric_help
    )
    parser.add_argument(
        "--plot", type=Path, metavar="FILE.png", help="draw the points, their CIs and the front"
    )
    parser.add_argument("--csv", type=Path, metavar="FILE.csv", help="write the points, to redraw them later")
    parser.add_argument("--ci", action="append", default=[], metavar="GROUP", help="draw this group's CIs")
    parser.add_argument(
        "--annotate", action="append", default=[], metavar="GROUP", help="name this group's points"
    )
    line_help = "a labelled reference line at x = VALUE; write a negative one as --{}-line=-224:TEXT"
    parser.add_argument("--x-line", action="append", default=[], type=_reference_line, metavar="VALUE:TEXT",
                        help=line_help.format("x"))  # fmt: skip
    parser.add_argument("--y-line", action="append", default=[], type=_reference_line, metavar="VALUE:TEXT",
                        help=line_help.replace("x =", "y =").format("y"))  # fmt: skip
    parser.add_argument("--title", help="the figure's title")
    args = parser.parse_args(argv)

    json_files = [f for f in args.files if not _is_csv(f)]
    if len(args.label) > len(json_files):
        parser.error(f"{len(args.label)} --label for {len(json_files)} JSON files")
    labels = iter(args.label)
    points: list[Point] = []
    try:
        for path in args.files:
            label = None if _is_csv(path) else next(labels, None)
            points.extend(_load(path, label, args.x, args.y))
    except (OSError, ValueError) as error:  # JSONDecodeError is a ValueError
        parser.error(str(error))
    if not points:
        parser.error("the files hold no models")
    groups = {p.group for p in points}
    for group in args.ci + args.annotate:
        if group not in groups:
            parser.error(f"no group {group!r}; the groups are {sorted(groups)}")
    has_front = BETTER.get(args.x) is not None and BETTER.get(args.y) is not None

    if args.csv:
        write_csv(points, args.csv, args.x, args.y)
    if args.plot:
        figure = tradeoff_figure(
            points, args.x, args.y, ci_groups=args.ci, annotate_groups=args.annotate,
            x_lines=args.x_line, y_lines=args.y_line, front=has_front, title=args.title,
        )  # fmt: skip
        args.plot.parent.mkdir(parents=True, exist_ok=True)
        figure.savefig(args.plot, dpi=110)
    if has_front:
        print(f"Pareto front of {len(points)} points, {args.x} against {args.y} (IQM [95 % CI]):")
        for p in pareto_front(points, args.x, args.y):
            print(f"  {p.group} / {p.name}: {p.x:.4g} [{p.x_lo:.4g}, {p.x_hi:.4g}]  "
                  f"{p.y:.4g} [{p.y_lo:.4g}, {p.y_hi:.4g}]  ({p.episodes} episodes)")  # fmt: skip
    else:
        print(f"{len(points)} points; no Pareto front, since {args.x} or {args.y} has no better side")
    return 0


if __name__ == "__main__":
    sys.exit(main())
