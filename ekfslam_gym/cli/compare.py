"""Compare two groups of models evaluated on the same seeds: the difference of their IQMs with a 95 % bootstrap
CI that resamples the seeds (see ``ekfslam_gym.evaluation.paired``).

ekfslam-compare --a new_s0.json new_s1.json --b old_s0.json old_s1.json [--key "ppo[model]"]
    [--metric map_log_det --metric landmark_rmse]

Each FILE holds the per-episode metrics that ``evaluate --episodes-json`` writes ({name: [episodes]}); every
entry of a file is one model of its group, or only the entry named ``--key`` (in every file) when given.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..evaluation.paired import Model, paired_difference
from ..evaluation.report import BETTER
from .common import command_line, command_parser

DEFAULT_METRICS = ("map_log_det", "landmark_rmse", "ate")


def _models(paths: list[Path], key: str | None) -> list[Model]:
    models: list[Model] = []
    for path in paths:
        entries = json.loads(path.read_text())
        if not isinstance(entries, dict) or not all(isinstance(v, list) for v in entries.values()):
            raise ValueError(
                f"{path}: expected {{name: [episode metrics]}} as evaluate --episodes-json writes"
            )
        if key is None:
            models.extend(entries.values())
        elif key in entries:
            models.append(entries[key])
        else:
            raise ValueError(f"{path} has no entry {key!r}; it has {sorted(entries)}")
    return models


@command_line("compare")
def main(argv: list[str] | None = None) -> int:
    parser = command_parser(
        "compare", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--a", nargs="+", type=Path, required=True, metavar="FILE", help="group a's files")
    parser.add_argument("--b", nargs="+", type=Path, required=True, metavar="FILE", help="group b's files")
    parser.add_argument("--key", help="take only this entry of each file (e.g. 'ppo[model]')")
    parser.add_argument("--metric", action="append", choices=sorted(BETTER), metavar="METRIC",
                        help="a metric to compare, repeatable (default: " + ", ".join(DEFAULT_METRICS) + ")")  # fmt: skip
    parser.add_argument(
        "--resamples", type=int, default=2000, help="bootstrap resamples (default %(default)s)"
    )
    args = parser.parse_args(argv)
    if args.resamples < 1:
        parser.error("--resamples must be at least 1")
    try:
        a, b = _models(args.a, args.key), _models(args.b, args.key)
        results = [
            paired_difference(a, b, m, n_resamples=args.resamples) for m in args.metric or DEFAULT_METRICS
        ]
    except (OSError, KeyError, ValueError) as error:
        # a JSONDecodeError is a ValueError; a KeyError is a metric the episodes lack
        parser.error(str(error))
    print(f"group a: {len(a)} models, group b: {len(b)} models, on {results[0].seeds} seeds; IQM over the pooled "
          "episodes, a - b with its 95 % CI over resampled seeds")  # fmt: skip
    for r in results:
        print(f"  {r.metric}: {r.a:.4g} - {r.b:.4g} = {r.difference:+.4g} [{r.ci[0]:+.4g}, {r.ci[1]:+.4g}]")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
