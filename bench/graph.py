"""Benchmark: the graph back end against GTSAM's Levenberg-Marquardt, each figure a ratio measured in this run.

    python bench/graph.py [--repeats 5] [--data DIR] [--poses 1000] [--landmarks 100] [--only victoria-park]

1. intel (course data, g2o form, 1728 poses): ours (GN and LM) vs GTSAM LM, at the same final error.
2. a bearing-range graph (≥ 1000 poses, 100 landmarks, from `synthetic_drive`) vs GTSAM with BearingRangeFactor2D.
3. dlr on its own (GTSAM's g2o reader drops EDGE_SE2_XY, so there is no GTSAM figure).
4. Victoria Park (GTSAM's victoria_park.txt, 6969 poses, 151 landmarks): ours as ``ekfslam-graph FILE --solver
   lm`` runs it (GTSAM's LM settings, `GTSAM_LM`) vs GTSAM's LM from load2D with a prior on pose 0, one run each
   in this process (GTSAM takes seconds); also both Gauss-Newtons.
5. the phases of one iteration (set-up, linearisation, factorisations, solve) on each graph.
6. our sparse backends against each other on each graph (how the default was chosen).

Errors are the course's F = Σ eᵀΩe; GTSAM's ``error()`` is F/2 and is doubled here. GTSAM's BetweenFactorPose2
uses the SE(2) logarithm where the course uses t2v, so the two optimise slightly different objectives: each
solution is scored by both and the final errors are compared in ours. Times are wall clock, best of `repeats`
interleaved runs (another process may share the machine), optimisation only: graph building and file reading are
excluded, our set-up (sparsity pattern, ordering) and GTSAM's (ordering, elimination tree) are included.
"""

from __future__ import annotations

import os

os.environ["OPENBLAS_NUM_THREADS"] = (
    "1"  # before numpy is imported: one core, like GTSAM's single thread here
)
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from ekfslam_gym.data.g2o import read_g2o  # noqa: E402
from ekfslam_gym.data.gtsam2d import read_gtsam2d  # noqa: E402
from ekfslam_gym.data.synthetic import synthetic_drive  # noqa: E402
from ekfslam_gym.graph.linear_system import NormalEquations  # noqa: E402
from ekfslam_gym.graph.optimizer import (  # noqa: E402
    GTSAM_LM,
    FactorGraph,
    Values,
    gauss_newton,
    levenberg_marquardt,
)
from ekfslam_gym.graph.smoother import build_drive_graph  # noqa: E402
from ekfslam_gym.graph.sparse_solve import available_backends, make_solver  # noqa: E402

try:
    import gtsam
except ImportError:  # optional: the `bench` extra
    gtsam = None

DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "freiburg"


def best_of(runs: dict[str, Callable[[], object]], repeats: int) -> dict[str, tuple[float, float, object]]:
    """(best, median, last result) seconds of each callable, the runs interleaved so that load hits all alike."""
    times: dict[str, list[float]] = {name: [] for name in runs}
    results: dict[str, object] = {}
    for _ in range(repeats):
        for name, run in runs.items():
            start = time.perf_counter()
            results[name] = run()
            times[name].append(time.perf_counter() - start)
    return {name: (min(t), statistics.median(t), results[name]) for name, t in times.items()}


def report(
    title: str,
    timings: dict[str, tuple[float, float, object]],
    errors: dict[str, float],
    reference: str | None,
) -> None:
    print(f"\n{title}")
    print(f"  {'solver':<24}{'best [s]':>10}{'median [s]':>12}{'final F (ours)':>18}{'time ratio':>12}")
    for name, (best, median, _) in timings.items():
        ratio = f"{best / timings[reference][0]:.2f}x" if reference in timings else ""
        print(f"  {name:<24}{best:>10.4f}{median:>12.4f}{errors[name]:>18.4f}{ratio:>12}")


# ---------------------------------------------------------------------------------------------------------------
# GTSAM side


def gtsam_pose_values(values: Values, pose_keys: list[int], landmark_keys: list[int]) -> object:
    out = gtsam.Values()
    for key, (x, y, th) in zip(pose_keys, values.poses, strict=True):
        out.insert(key, gtsam.Pose2(x, y, th))
    for key, p in zip(landmark_keys, values.landmarks, strict=True):
        out.insert(key, np.asarray(p, dtype=float))
    return out


def our_values(result: object, pose_keys: list[int], landmark_keys: list[int]) -> Values:
    poses = [result.atPose2(k) for k in pose_keys]
    return Values(
        [[p.x(), p.y(), p.theta()] for p in poses],
        np.array([result.atPoint2(k) for k in landmark_keys]).reshape(-1, 2),
    )


def gtsam_lm(graph: object, initial: object) -> tuple[object, int]:
    params = gtsam.LevenbergMarquardtParams()  # defaults: λ₀ 1e-5, relative/absolute error tolerance 1e-5
    optimizer = gtsam.LevenbergMarquardtOptimizer(graph, initial, params)
    return optimizer.optimize(), optimizer.iterations()


def gtsam_graph_of(graph: FactorGraph, pose_keys: list[int], landmark_keys: list[int]) -> object:
    """The same factors in GTSAM: PriorFactorPose2, BetweenFactorPose2, BearingRangeFactor2D."""
    out = gtsam.NonlinearFactorGraph()
    f = graph.prior
    for i, z, info in zip(f.first, f.measured, f.information, strict=True):
        out.add(
            gtsam.PriorFactorPose2(pose_keys[i], gtsam.Pose2(*z), gtsam.noiseModel.Gaussian.Information(info))
        )
    f = graph.between
    for i, j, z, info in zip(f.first, f.second, f.measured, f.information, strict=True):
        out.add(
            gtsam.BetweenFactorPose2(
                pose_keys[i], pose_keys[j], gtsam.Pose2(*z), gtsam.noiseModel.Gaussian.Information(info)
            )
        )
    f = graph.range_bearing
    for i, l, z, info in zip(f.first, f.second, f.measured, f.information, strict=True):
        # GTSAM orders the reading (bearing, range); ours is (range, bearing).
        noise = gtsam.noiseModel.Gaussian.Information(np.ascontiguousarray(info[::-1, ::-1]))
        out.add(gtsam.BearingRangeFactor2D(pose_keys[i], landmark_keys[l], gtsam.Rot2(z[1]), z[0], noise))
    return out


# ---------------------------------------------------------------------------------------------------------------
# The three benchmarks


def bench_intel(path: Path, repeats: int) -> list[float]:
    problem = read_g2o(path)
    graph, initial = problem.graph, problem.initial
    runs: dict[str, Callable[[], object]] = {
        "ours GN": lambda: gauss_newton(graph, initial),
        "ours LM": lambda: levenberg_marquardt(graph, initial),
    }
    if gtsam is not None:
        g_graph, g_initial = gtsam.readG2o(str(path), False)
        pose_keys = [int(k) for k in problem.pose_ids]
        # Gauge: a unit prior on the first pose, GTSAM's version of the course's H[0:3, 0:3] += I.
        anchored = gtsam.NonlinearFactorGraph(g_graph)
        anchored.add(
            gtsam.PriorFactorPose2(
                pose_keys[0], g_initial.atPose2(pose_keys[0]), gtsam.noiseModel.Unit.Create(3)
            )
        )
        runs["GTSAM LM"] = lambda: gtsam_lm(anchored, g_initial)
    timings = best_of(runs, repeats)
    errors = {name: timings[name][2].final_error for name in ("ours GN", "ours LM")}
    print(f"\nintel.g2o: {initial.num_poses} poses, {len(graph)} edges; F₀ = {graph.error(initial):.2f}")
    keys = (pose_keys, []) if gtsam is not None else None
    return compare_with_gtsam("intel", graph, g_graph if keys else None, keys, timings, errors)


def bench_bearing_range(num_poses: int, num_landmarks: int, repeats: int) -> list[float]:
    # Every landmark must be seen, or it would be no variable; the arena and range are chosen for that.
    drive = synthetic_drive(num_poses - 1, num_landmarks, seed=7, arena=30.0, max_range=8.0, step_length=0.5)
    built = build_drive_graph(
        drive.true_poses[0], drive.odometry, drive.odometry_cov, drive.readings, drive.reading_cov
    )
    graph, initial = built.graph, built.initial
    print(
        f"\nbearing-range graph: {initial.num_poses} poses, {initial.num_landmarks} landmarks, "
        f"{len(graph.between)} odometry edges, {len(graph.range_bearing)} range-bearing edges; "
        f"F₀ = {graph.error(initial):.1f}"
    )
    runs: dict[str, Callable[[], object]] = {
        "ours GN": lambda: gauss_newton(graph, initial),
        "ours LM": lambda: levenberg_marquardt(graph, initial),
    }
    if gtsam is not None:
        pose_keys = [gtsam.symbol("x", i) for i in range(initial.num_poses)]
        landmark_keys = [gtsam.symbol("l", i) for i in range(initial.num_landmarks)]
        g_graph = gtsam_graph_of(graph, pose_keys, landmark_keys)
        g_initial = gtsam_pose_values(initial, pose_keys, landmark_keys)
        runs["GTSAM LM"] = lambda: gtsam_lm(g_graph, g_initial)
    timings = best_of(runs, repeats)
    errors = {name: timings[name][2].final_error for name in ("ours GN", "ours LM")}
    keys = (pose_keys, landmark_keys) if gtsam is not None else None
    return compare_with_gtsam("bearing-range", graph, g_graph if keys else None, keys, timings, errors)


def compare_with_gtsam(label, graph, g_graph, keys, timings, errors) -> list[float]:
    """Print iterations, the final errors scored both ways and the times; returns ours / GTSAM time ratios.

    GTSAM's error is half the course's sum of e^T Omega e, and its pose-pose factor uses the SE(2) log
    rather than t2v, so its solution is scored with our error to compare final errors."""
    for name in ("ours GN", "ours LM"):
        r = timings[name][2]
        print(f"  {name}: {r.iterations} iterations, {r.linear_solves} factorisations ({r.backend})")
    ratios = []
    if g_graph is not None:
        pose_keys, landmark_keys = keys
        g_result, g_iterations = timings["GTSAM LM"][2]
        errors["GTSAM LM"] = graph.error(our_values(g_result, pose_keys, landmark_keys))
        ours_in_gtsam = 2 * g_graph.error(
            gtsam_pose_values(timings["ours GN"][2].values, pose_keys, landmark_keys)
        )
        print(
            f"  GTSAM LM: {g_iterations} iterations; its own 2·error {2 * g_graph.error(g_result):.4f}, "
            f"ours scored by GTSAM {ours_in_gtsam:.4f}"
        )
        rel = abs(errors["ours GN"] - errors["GTSAM LM"]) / errors["GTSAM LM"]
        print(f"  same final error: |F_ours − F_GTSAM| / F_GTSAM = {rel:.1e} (course metric)")
        ratios = [timings[n][0] / timings["GTSAM LM"][0] for n in ("ours GN", "ours LM")]
    else:
        print("  GTSAM not installed (pip install gtsam, the `bench` extra): no comparison")
    report(f"{label}: times", timings, errors, "GTSAM LM" if g_graph is not None else None)
    return ratios


def bench_dlr(path: Path, repeats: int) -> None:
    problem = read_g2o(path)
    graph, initial = problem.graph, problem.initial
    timings = best_of(
        {
            "ours GN": lambda: gauss_newton(graph, initial),
            "ours LM": lambda: levenberg_marquardt(graph, initial),
        },
        repeats,
    )
    print(
        f"\ndlr.g2o: {initial.num_poses} poses, {initial.num_landmarks} landmarks, {len(graph)} edges "
        "(no GTSAM figure: its g2o reader drops EDGE_SE2_XY)"
    )
    for name in timings:
        r = timings[name][2]
        print(f"  {name}: {r.iterations} iterations, F {r.initial_error:.2f} → {r.final_error:.4f}")
    report("dlr: times", timings, {n: t[2].final_error for n, t in timings.items()}, None)


def bench_victoria_park(path: Path, repeats: int) -> list[float]:
    """Ours (GTSAM's LM settings, the CLI's choice for this file) against GTSAM's LM, one run each by default.

    GTSAM's graph is its own load2D of the file plus a prior on pose 0 at its initial value with variances (1e-6,
    1e-6, 1e-8), the prior of GTSAM's Pose2SLAMExample_g2o: with it GTSAM's LM reproduces the data folder's README
    (64 iterations, 210,660; a unit prior ends at 207,208, sigmas (0.3, 0.3, 0.1) at 221,307). Ours holds pose 0
    with the course's gauge instead. Both start from the odometry-composed poses."""
    data = read_gtsam2d(path)
    problem = data.to_problem()
    graph, initial = problem.graph, problem.initial
    print(
        f"\nvictoria_park.txt: {initial.num_poses} poses, {initial.num_landmarks} landmarks, {len(graph)} factors; "
        f"F₀ = {graph.error(initial):.2f}"
    )
    runs: dict[str, Callable[[], object]] = {
        "ours LM": lambda: levenberg_marquardt(graph, initial, **GTSAM_LM),
        "ours GN": lambda: gauss_newton(graph, initial),
    }
    if gtsam is not None:
        g_plain, g_initial = gtsam.load2D(str(path))
        g_graph = gtsam.NonlinearFactorGraph(g_plain)
        g_graph.add(
            gtsam.PriorFactorPose2(
                0, g_initial.atPose2(0), gtsam.noiseModel.Diagonal.Variances(np.array([1e-6, 1e-6, 1e-8]))
            )
        )

        def g_gauss_newton() -> tuple[object, int]:
            optimizer = gtsam.GaussNewtonOptimizer(g_graph, g_initial, gtsam.GaussNewtonParams())
            return optimizer.optimize(), optimizer.iterations()

        runs["GTSAM LM"] = lambda: gtsam_lm(g_graph, g_initial)
        runs["GTSAM GN"] = g_gauss_newton
    timings = best_of(runs, repeats)
    pose_keys = [int(k) for k in data.pose_ids]
    landmark_keys = [gtsam.symbol("l", int(k)) for k in data.landmark_ids] if gtsam is not None else []
    errors = {}
    for name in ("ours LM", "ours GN"):
        r = timings[name][2]
        errors[name] = r.final_error
        scored = ""
        if gtsam is not None:
            # Without the prior: ours holds pose 0 by the gauge, not at GTSAM's prior.
            g_values = gtsam_pose_values(r.values, pose_keys, landmark_keys)
            scored = f", scored by GTSAM (prior left out) {2 * g_plain.error(g_values):.1f}"
        print(
            f"  {name}: {r.iterations} iterations, {r.linear_solves} factorisations ({r.backend}), "
            f"final χ² {r.final_error:.1f}{scored}"
        )
    ratios = []
    if gtsam is not None:
        for name in ("GTSAM LM", "GTSAM GN"):
            g_result, g_iterations = timings[name][2]
            errors[name] = graph.error(our_values(g_result, pose_keys, landmark_keys))
            print(
                f"  {name}: {g_iterations} iterations, its own 2·error {2 * g_graph.error(g_result):.1f}, "
                f"scored by ours {errors[name]:.1f}"
            )
        ratios = [timings[n][0] / timings["GTSAM LM"][0] for n in ("ours GN", "ours LM")]
        lm = errors["ours LM"] / (2 * g_graph.error(timings["GTSAM LM"][2][0]))
        print(f"  ours LM χ² / GTSAM LM 2·error = {lm:.4f}; target ≤ 210,660 × 1.001 = {210_660 * 1.001:.0f}")
    else:
        print("  GTSAM not installed (pip install gtsam, the `bench` extra): no comparison")
    report("victoria park: times", timings, errors, "GTSAM LM" if gtsam is not None else None)
    return ratios


def bench_phases(problems: dict[str, tuple[FactorGraph, Values]], repeats: int) -> None:
    """Where one Gauss-Newton iteration spends its time (default backend), best of `repeats` each."""
    print(
        "\nphases of the default backend [ms] (set-up and first factorisation once, the rest per iteration):"
    )
    print(
        f"  {'graph':<16}{'set-up':>9}{'linearize':>11}{'1st factor':>12}{'refactor':>10}{'solve':>8}{'error':>8}"
    )
    for name, (graph, initial) in problems.items():
        x = initial.to_vector()

        def best(run: Callable[[], object]) -> float:
            return 1e3 * best_of({"run": run}, repeats)["run"][0]

        setup = best(lambda g=graph, v=initial: NormalEquations(g, v.num_poses, v.num_landmarks))
        system = NormalEquations(graph, initial.num_poses, initial.num_landmarks)
        linearize = best(lambda s=system, x=x: s.linearize(x))
        hdata, b, _ = system.linearize(x)
        hdata[system.diagonal[:3]] += 1.0
        first = best(lambda s=system, h=hdata: make_solver(s.pattern).factorize(h))
        solver = make_solver(system.pattern)
        solver.factorize(hdata)
        refactor = best(lambda h=hdata, sv=solver: sv.factorize(h))
        solve = best(lambda b=b, sv=solver: sv.solve(b))
        error = best(lambda s=system, x=x: s.error(x))
        print(
            f"  {name:<16}{setup:>9.2f}{linearize:>11.2f}{first:>12.2f}{refactor:>10.2f}{solve:>8.2f}{error:>8.2f}"
        )


def bench_backends(problems: dict[str, tuple[FactorGraph, Values]], repeats: int) -> None:
    backends = available_backends()
    if "superlu" not in backends:
        backends.append("superlu")
    print(f"\nsparse backends (GN, best of {repeats}; 'auto' picks {backends[0]}):")
    print(f"  {'graph':<16}" + "".join(f"{b:>12}" for b in backends) + f"{'ratios to ' + backends[0]:>28}")
    for name, (graph, initial) in problems.items():
        runs = {b: (lambda b=b, g=graph, x=initial: gauss_newton(g, x, backend=b)) for b in backends}
        timings = best_of(runs, repeats)
        base = timings[backends[0]][0]
        ratios = " ".join(f"{timings[b][0] / base:.2f}x" for b in backends)
        print(f"  {name:<16}" + "".join(f"{timings[b][0]:>12.4f}" for b in backends) + f"{ratios:>28}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--data", type=Path, default=Path(os.environ.get("EKFSLAM_DATA_DIR", DEFAULT_DATA)))
    parser.add_argument("--poses", type=int, default=1000)
    parser.add_argument("--landmarks", type=int, default=100)
    parser.add_argument(
        "--victoria-park", type=Path, default=DEFAULT_DATA.parent / "victoria_park" / "victoria_park.txt"
    )
    parser.add_argument("--only", choices=("victoria-park",), help="run one benchmark alone")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: a check that the script runs")
    args = parser.parse_args(argv)
    data = args.data / "freiburg" if (args.data / "freiburg").is_dir() else args.data
    if args.smoke:  # the synthetic graph only, small
        args.repeats, args.poses, args.landmarks, data = 1, 60, 10, Path(os.devnull)
    if gtsam is None:
        print("GTSAM is not installed (pip install gtsam, the `bench` extra): timing ours alone.")

    summary = {}
    if args.only == "victoria-park":
        summary["victoria-park"] = bench_victoria_park(args.victoria_park, 1)
        print_summary(summary)
        return 0
    intel, dlr = data / "intel.g2o", data / "dlr.g2o"
    if intel.is_file():
        summary["intel"] = bench_intel(intel, args.repeats)
    else:
        print(f"\nintel.g2o not found in {data}: skipped")
    summary["bearing-range"] = bench_bearing_range(args.poses, args.landmarks, args.repeats)
    if dlr.is_file():
        bench_dlr(dlr, args.repeats)
    else:
        print(f"\ndlr.g2o not found in {data}: skipped")

    problems = {}
    for name, path in (("intel", intel), ("dlr", dlr)):
        if path.is_file():
            p = read_g2o(path)
            problems[name] = (p.graph, p.initial)
    drive = synthetic_drive(args.poses - 1, args.landmarks, seed=7, arena=30.0, max_range=8.0)
    built = build_drive_graph(
        drive.true_poses[0], drive.odometry, drive.odometry_cov, drive.readings, drive.reading_cov
    )
    problems["bearing-range"] = (built.graph, built.initial)
    if not args.smoke and args.victoria_park.is_file():
        summary["victoria-park"] = bench_victoria_park(args.victoria_park, 1)
    bench_phases(problems, args.repeats)
    bench_backends(problems, max(1, args.repeats // 2))
    print_summary(summary)
    return 0


def print_summary(summary: dict[str, list[float]]) -> None:
    if any(summary.values()):
        print("\nsummary (ours / GTSAM LM, best times; target ≤ 1.5x, Victoria Park ≤ 1x):")
        for name, ratios in summary.items():
            if ratios:
                print(f"  {name:<16} GN {ratios[0]:.2f}x   LM {ratios[1]:.2f}x")


if __name__ == "__main__":
    sys.exit(main())
