"""Draw docs/victoria_park.png: Victoria Park optimised by Levenberg-Marquardt with GTSAM's settings (what
``ekfslam-graph victoria_park.txt --solver lm`` runs) and by the course's Gauss-Newton, beside each other.

    python docs/victoria_park.py [PATH/victoria_park.txt] [--out docs/victoria_park.png]

The file is GTSAM's examples/Data/victoria_park.txt (BSD licence); by default it is looked for in
../shared/data/victoria_park beside the repository.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ekfslam_gym.data.gtsam2d import read_gtsam2d
from ekfslam_gym.evaluation.plotting import draw_graph_solution
from ekfslam_gym.graph.optimizer import GTSAM_LM, gauss_newton, levenberg_marquardt

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_FILE = ROOT.parent / "shared" / "data" / "victoria_park" / "victoria_park.txt"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("file", type=Path, nargs="?", default=DEFAULT_FILE)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "victoria_park.png")
    args = parser.parse_args(argv)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    problem = read_gtsam2d(args.file).to_problem()
    runs = {
        "LM, GTSAM's settings": levenberg_marquardt(problem.graph, problem.initial, **GTSAM_LM),
        "GN, the course's": gauss_newton(problem.graph, problem.initial),
    }
    fig = Figure(figsize=(13, 6.5), dpi=100)
    FigureCanvasAgg(fig)
    for k, (title, result) in enumerate(runs.items()):
        draw_graph_solution(fig.add_subplot(1, 2, k + 1), problem.initial, result, title)
        print(f"{title}: χ² {result.final_error:.1f} after {result.iterations} iterations")
    fig.suptitle("Victoria Park: dead reckoning (grey) and the optimised drive and trees (χ² = F = Σ eᵀΩe)")
    fig.tight_layout()
    fig.savefig(args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
