"""Solve a pose graph from the command line.

    ekfslam-graph FILE [--solver gn|lm] [--settings auto|course|gtsam] [--json] [--plot FILE.png]
                          [--backend NAME]

FILE is a course MAT graph (``.dat``), a 2-D g2o file (``.g2o``) or a GTSAM 2-D dataset (``.txt``/``.graph``,
e.g. Victoria Park). ``--settings gtsam`` optimises as GTSAM does (its Pose2 retraction, and for LM its λ
schedule, `GTSAM_LM`); ``auto`` picks it for GTSAM files and the course's settings otherwise. ``--json`` prints
exactly one JSON object
``{"initial_error", "final_error", "iterations", "seconds", "poses", "landmarks"}``; errors are the course's
F = Σ eᵀΩe and ``seconds`` times the optimisation alone (reading the file excluded).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from .common import command_line, command_parser, refuse

# ``graph.sparse_solve.BACKENDS`` and "auto", written out: importing the graph package (SciPy's sparse matrices)
# would double --help's time. tests/cli/test_command_lines.py holds them equal.
BACKEND_CHOICES = ("auto", "qdldl", "cholmod", "superlu")


@command_line("graph")
def main(argv: Sequence[str] | None = None) -> int:
    parser = command_parser("graph", description=__doc__.split("\n\n")[0])
    parser.add_argument("file", type=Path, help="graph file: .dat (course MAT), .g2o, or GTSAM .txt/.graph")
    parser.add_argument(
        "--solver", choices=("gn", "lm"), default="gn", help="Gauss-Newton or Levenberg-Marquardt"
    )
    parser.add_argument("--backend", choices=BACKEND_CHOICES, default="auto", help="sparse factorisation")
    parser.add_argument(
        "--settings",
        choices=("auto", "course", "gtsam"),
        default="auto",
        help="optimiser conventions: the course's (x + dx) or GTSAM's (exp map; LM's lambda schedule); "
        "auto: gtsam for .txt/.graph files",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object with the figures")
    parser.add_argument("--plot", type=Path, metavar="FILE.png", help="save a plot of the solution")
    args = parser.parse_args(argv)
    from ..data.graph_files import GTSAM_SUFFIXES, read_graph
    from ..graph.optimizer import GTSAM_LM, optimize

    try:  # a missing or malformed file is the user's input: one line naming it (and the line), exit 2
        problem = read_graph(args.file)
    except (OSError, ValueError) as error:
        refuse(parser, "", error)
    settings = args.settings
    if settings == "auto":
        settings = "gtsam" if args.file.suffix.lower() in GTSAM_SUFFIXES else "course"
    options: dict[str, object] = {}
    if settings == "gtsam":
        options = dict(GTSAM_LM) if args.solver == "lm" else {"retraction": GTSAM_LM["retraction"]}
    result = optimize(problem.graph, problem.initial, args.solver, backend=args.backend, **options)

    if args.json:
        summary = {
            "initial_error": result.initial_error,
            "final_error": result.final_error,
            "iterations": result.iterations,
            "seconds": result.seconds,
            "poses": problem.initial.num_poses,
            "landmarks": problem.initial.num_landmarks,
        }
        print(json.dumps(summary))
    else:
        print(
            f"{args.file.name}: {problem.initial.num_poses} poses, {problem.initial.num_landmarks} landmarks, "
            f"{len(problem.graph)} edges; {args.solver.upper()} with {result.backend}"
        )
        for k, err in enumerate(result.errors):
            print(f"  iteration {k:3d}  error {err:.6f}")
        if result.diverged:
            print(
                f"Gauss-Newton diverged: the error rose from {result.initial_error:.6g} to "
                f"{result.final_error:.6g} ({result.final_error / result.initial_error:.3g} times) in "
                f"{result.iterations} iterations without converging; try --solver lm"
            )
        status = "converged" if result.converged else "stopped without converging"
        print(
            f"{status} after {result.iterations} iterations in {result.seconds:.3f} s ({settings} settings)"
        )
    if args.plot is not None:
        from ..evaluation.plotting import plot_graph_solution

        plot_graph_solution(args.plot, problem.initial, result, title=args.file.name)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
