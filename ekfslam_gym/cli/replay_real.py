"""``ekfslam-replay`` on a real robot's data set: the options, the data set's detection, and the report.

``--dataset mrclam`` (or ``--data`` naming a folder that holds ``Barcodes.dat``): UTIAS MRCLAM robot 1, replayed
with the velocity model (``evaluation.mrclam``): ``--noise textbook`` (the default: range 0.15 m, bearing 0.08 rad)
or ``--noise fitted`` (maximum likelihood on this drive, ``evaluation.mrclam.FITTED_MRCLAM``).
The report lists each landmark's error after the best SE(2) alignment to the survey, NIS against its chi^2 band
(real data has no pose truth), the filter's time per step and, with ``--association nearest|jcbc`` (barcodes
hidden), the false and missed associations counted against the barcodes. ``--smoother`` adds the full-SLAM
smoother of the same data (``evaluation.drive_smoother``): its chi^2 and its trajectory's distance to the
filter's.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from ..evaluation.report import json_safe

DATASETS = ("course", "mrclam", "gtsam")
# the first tag of a GTSAM 2-D file (``data.gtsam2d``); the course's files start with a 4-field ODOMETRY line
_GTSAM_TAGS = (
    "VERTEX_SE2",
    "VERTEX2",
    "VERTEX",
    "VERTEX_XY",
    "ODOMETRY",
    "EDGE_SE2",
    "EDGE2",
    "EDGE",
    "LANDMARK",
    "BR",
)
VARIANTS = ("ekf", "fej", "iekf")
ASSOCIATIONS = ("known", "nearest", "jcbc")
NOISES = ("textbook", "fitted")


def add_real_data_arguments(parser: argparse.ArgumentParser) -> None:
    """The real data sets' options (ignored by the course files and the simulated drive)."""
    parser.add_argument(
        "--dataset",
        choices=DATASETS,
        default=None,
        help="the format of --data (default: detected): course files, an MRCLAM folder (it holds Barcodes.dat) "
        "or a GTSAM 2-D file such as Victoria Park's",
    )
    parser.add_argument("--variant", choices=VARIANTS, default=None, help="filter variant (real data; ekf)")
    parser.add_argument(
        "--association",
        choices=ASSOCIATIONS,
        default=None,
        help="known: by barcode; nearest or jcbc: barcodes hidden, counted against them (real data; known)",
    )
    parser.add_argument(
        "--robots",
        action="store_true",
        help="MRCLAM: also give the filter the readings of the other robots' barcodes (moving objects)",
    )
    parser.add_argument(
        "--team",
        action="store_true",
        help="MRCLAM: all five robots in one joint filter (robot-to-robot readings fused), beside each alone",
    )
    parser.add_argument(
        "--noise",
        choices=NOISES,
        default=None,
        help="MRCLAM: textbook (range 0.15 m, bearing 0.08 rad) or fitted by maximum likelihood (textbook)",
    )
    parser.add_argument(
        "--smoother", action="store_true", help="also run the full-SLAM smoother on the same data (known)"
    )


def resolve_dataset(parser: argparse.ArgumentParser, args: argparse.Namespace) -> str:
    """The data set ``args`` asks for: ``--dataset``, else detected from ``--data`` (and set there); refuses the
    options that do not apply to it."""
    dataset = args.dataset = args.dataset if args.dataset is not None else _detect(args.data)
    real_only = {
        "--variant": args.variant is not None,
        "--association": args.association is not None,
        "--robots": args.robots,
        "--team": args.team,
        "--noise": args.noise is not None,
        "--smoother": args.smoother,
    }
    if dataset == "course":
        used = [name for name, given in real_only.items() if given]
        if used:
            parser.error(f"{', '.join(used)} apply to a real data set (--dataset mrclam or gtsam)")
        return dataset
    if args.data is None:
        parser.error(f"--dataset {dataset} needs --data (the data set's folder or file)")
    course_only = {
        "--world": args.world is not None,
        "--seed": args.seed is not None,
        "--steps": args.steps is not None,
        "--sequential": args.sequential,
        "--gif": args.gif is not None,
        "--save-state": args.save_state is not None,
        "--tum": args.tum is not None,
    }
    used = [name for name, given in course_only.items() if given]
    if used:
        parser.error(f"{', '.join(used)} do not apply to --dataset {dataset}")
    if dataset == "gtsam":
        used = [name for name, given in (("--association", args.association), ("--robots", args.robots),
                                         ("--team", args.team), ("--noise", args.noise)) if given]  # fmt: skip
        if used:
            parser.error(
                f"{', '.join(used)} apply to --dataset mrclam only (GTSAM files give identities and noise)"
            )
    if args.team and (args.robots or args.smoother or args.association not in (None, "known")):
        parser.error(
            "--team reads the barcodes of landmarks and robots: no --robots, --smoother or --association"
        )
    if args.smoother and args.association not in (None, "known"):
        parser.error("--smoother uses the barcodes: it needs --association known")
    if args.plot is not None and args.plot.suffix.lower() != ".png":
        parser.error(f"--plot needs a .png file name, got {args.plot}")
    return dataset


def _detect(data: Path | None) -> str:
    if data is None:
        return "course"
    data = Path(data)
    if (data / "Barcodes.dat").is_file():
        return "mrclam"
    if data.is_file():
        with data.open("r", encoding="ascii", errors="replace") as handle:
            for line in handle:
                tokens = line.split()
                if tokens:
                    course = tokens[0] in ("ODOMETRY", "SENSOR") and len(tokens) == 4
                    return "gtsam" if tokens[0] in _GTSAM_TAGS and not course else "course"
    return "course"


def replay_real_data(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """Replay a real data set and print the report (or one JSON object with ``--json``)."""
    if args.dataset == "gtsam":
        return _replay_gtsam(parser, args)
    if args.team:
        from .replay_team import replay_team_data

        return replay_team_data(parser, args)
    return _replay_mrclam(parser, args)


def _replay_gtsam(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """A GTSAM 2-D file's odometry chain and readings through the filter (``evaluation.chain_replay``)."""
    from ..data.gtsam2d import read_gtsam2d
    from ..evaluation.chain_replay import anchored_at_first_pose, replay_chain
    from ..evaluation.real_data import nis_summary, save_trajectory_picture

    try:
        dataset = read_gtsam2d(args.data)
        result = replay_chain(dataset, args.variant or "ekf")
    except (OSError, ValueError) as error:
        parser.error(str(error))
    figures = {
        "variant": args.variant or "ekf",
        "steps": result.steps,
        "landmarks_mapped": int(result.ekf.observed.sum()),
        "nis": nis_summary(result.nis),
        "seconds": result.seconds,
        "microseconds_per_step": 1e6 * result.seconds / max(result.steps, 1),
    }
    smoothed = None
    if args.smoother:
        from ..graph.optimizer import GTSAM_LM, optimize

        problem = dataset.to_problem()
        smoothed = optimize(problem.graph, problem.initial, "lm", **GTSAM_LM)
        smoothed_poses = anchored_at_first_pose(smoothed.values.poses).poses(smoothed.values.poses)
        gap = np.hypot(*(smoothed_poses[:, :2] - result.poses[:, :2]).T)
        figures["smoother"] = {
            "chi2": smoothed.final_error,
            "iterations": smoothed.iterations,
            "seconds": smoothed.seconds,
            "trajectory_gap_rms": float(np.sqrt(np.mean(gap**2))),
            "trajectory_gap_max": float(gap.max()),
        }
    if args.plot is not None:
        save_trajectory_picture(
            args.plot, result.poses, result.ekf.landmarks[result.ekf.observed],
            result.ekf.landmark_covs()[result.ekf.observed],
            smoothed=None if smoothed is None else smoothed_poses, title=f"{args.data}: {figures['variant']}",
        )  # fmt: skip
    if args.json:
        print(json.dumps(json_safe(figures), allow_nan=False))
        return 0
    nis = figures["nis"]
    print(
        f"EKF-SLAM ({figures['variant']}) on {args.data}: {result.steps} steps, "
        f"{figures['microseconds_per_step']:.0f} us per step, {figures['landmarks_mapped']} landmarks\n"
        f"NIS: mean {nis['mean']:.2f} over {nis['readings']} re-observations (2 dof: 2), "
        f"{100 * nis['inside']:.1f} % inside the 95 % band"
    )
    if smoothed is not None:
        s = figures["smoother"]
        print(
            f"smoother (LM): chi2 {s['chi2']:.0f}, {s['iterations']} iterations, {s['seconds']:.1f} s; trajectory "
            f"vs filter {s['trajectory_gap_rms']:.2f} m rms, {s['trajectory_gap_max']:.2f} m max"
        )
    return 0


def _replay_mrclam(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """Replay MRCLAM robot 1."""
    import dataclasses

    from ..data.mrclam import load_mrclam
    from ..evaluation.mrclam import FITTED_MRCLAM, ReplaySettings, build_drive, landmark_errors, replay_drive
    from ..evaluation.real_data import save_map_picture, summarise

    try:
        run = load_mrclam(args.data)
    except (OSError, ValueError) as error:
        parser.error(str(error))
    settings = dataclasses.replace(
        FITTED_MRCLAM if args.noise == "fitted" else ReplaySettings(),
        variant=args.variant or "ekf",
        association=args.association or "known",
    )
    drive = build_drive(run, robots=args.robots)
    result = replay_drive(drive, run.landmarks.ids, settings)
    figures = summarise(result, run.landmarks.ids, run.landmarks.positions)
    smoothing = None
    if args.smoother:
        from ..evaluation.drive_smoother import smooth_keyframes

        smoothing = smooth_keyframes(drive, run.landmarks.ids, settings, result.poses)
        gap = np.hypot(*(smoothing.poses[:, :2] - result.poses[smoothing.keyframes + 1, :2]).T)
        estimates = {
            int(i): xy for i, xy in zip(run.landmarks.ids, smoothing.landmarks) if np.all(np.isfinite(xy))
        }
        errors, _ = landmark_errors(estimates, run.landmarks.ids, run.landmarks.positions)
        figures["smoother"] = {
            "chi2": smoothing.chi2,
            "dof": smoothing.dof,
            "iterations": smoothing.result.iterations,
            "seconds": smoothing.result.seconds,
            "trajectory_gap_rms": float(np.sqrt(np.mean(gap**2))),
            "trajectory_gap_max": float(gap.max()),
            "landmark_errors": {str(k): v for k, v in sorted(errors.items())},
            "median_error": float(np.median(list(errors.values()))),
        }
    if args.plot is not None:
        _, transform = landmark_errors(
            result.landmark_estimates(), run.landmarks.ids, run.landmarks.positions
        )
        save_map_picture(
            args.plot, result, transform, run.landmarks.ids, run.landmarks.positions,
            None if smoothing is None else smoothing.poses,
            f"MRCLAM robot 1, {settings.variant}, {settings.association} association",
        )  # fmt: skip
    if args.json:
        print(json.dumps(json_safe(figures), allow_nan=False))
    else:
        print(_text(figures, args.data))
    return 0


def _text(figures: dict, source: Path) -> str:
    nis = figures["nis"]
    lines = [
        f"EKF-SLAM ({figures['variant']}, {figures['association']} association) on {source}: "
        f"{figures['steps']} steps, {figures['microseconds_per_step']:.1f} us per step "
        f"({figures['seconds']:.2f} s in the filter)",
        f"NIS: mean {nis['mean']:.2f} over {nis['readings']} re-observations (2 dof: 2), "
        f"{100 * nis['inside']:.1f} % inside the 95 % band, {100 * nis['windows_inside']:.0f} % of "
        f"{nis['window']}-reading means inside theirs",
        f"landmarks after SE(2) alignment to the survey: median {figures['median_error']:.3f} m, "
        f"{figures['within_0.18']} of {figures['landmarks_mapped']} within 0.18 m",
    ]
    lines += [f"  {k:>3}: {v:.3f} m" for k, v in figures["landmark_errors"].items()]
    if figures["association"] != "known":
        lines.append(
            f"associations against the barcodes: {figures['false_associations']} false, "
            f"{figures['missed_associations']} missed, {figures['new_landmarks']} landmarks started"
        )
    if "smoother" in figures:
        s = figures["smoother"]
        lines.append(
            f"smoother: chi2 {s['chi2']:.1f} for {s['dof']} dof, {s['iterations']} LM iterations, "
            f"{s['seconds']:.1f} s; trajectory vs filter: {s['trajectory_gap_rms']:.3f} m rms, "
            f"{s['trajectory_gap_max']:.3f} m max; landmark median {s['median_error']:.3f} m"
        )
    return "\n".join(lines)
