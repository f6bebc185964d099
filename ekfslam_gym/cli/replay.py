"""Replay a drive through EKF-SLAM: the project's simulated drive by default, course-format files, or a real
robot's data set (``--dataset mrclam``, see ``cli.replay_real``).

    ekfslam-replay [--data PATH [--world PATH]] [--steps N] [--sequential]
        [--init {course,inverse}] [--seed S] [--json] [--save-state FILE.npz]
        [--plot FILE.png] [--gif FILE.gif] [--tum FILE]
    ekfslam-replay --data MRCLAM_FOLDER [--dataset mrclam] [--variant {ekf,fej,iekf}]
        [--association {known,nearest,jcbc}] [--robots] [--smoother] [--json] [--plot FILE.png]

Defaults are the course's EKF-SLAM exercise (Freiburg *Robot Mapping*): R = diag(0.1, 0.1, 0.01) on the pose, Q = 0.01 I per reading, landmark
prior 1000, zero pose prior at the origin, course initialisation, batch update, every block read (331 steps
on the course file; ``--steps 330`` gives the course framework's run). Landmark slots follow the sorted world
ids, or ids 1..max id seen when there is no world file.

``--tum FILE`` writes the estimated trajectory (the start and the pose after each step, t = 0..N) as a TUM file
for the evo tools and, for the simulated drive, the true one beside it as ``<stem>_true<suffix>`` (``run.tum``
and ``run_true.tum``). Course-format files carry no true trajectory: with ``--data`` only the estimate is
written. The course format has no clock either: a step's timestamp is its index, in seconds.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from ..filter.settings import COURSE_SETTINGS, INIT_MODES
from .common import command_line, command_parser, refuse
from .replay_real import add_real_data_arguments, replay_real_data, resolve_dataset

if TYPE_CHECKING:
    from ..data.course import LandmarkMap
    from ..replay.result import Replay

MAX_GIF_FRAMES = 80  # enough for a smooth loop, few enough to render in seconds


def _report(result: Replay, world: LandmarkMap | None, source: str, n_readings: int) -> str:
    import numpy as np

    from ..angles import wrap_angle
    from ..replay.course import map_errors, map_rmse

    ekf = result.ekf
    x, y, theta = ekf.pose
    lines = [
        f"EKF-SLAM replay of {source}: {result.steps} steps, {n_readings} readings, "
        f"{int(ekf.observed.sum())} of {len(result.labels)} landmarks observed",
        f"final pose       x = {x:.6f} m, y = {y:.6f} m, theta = {theta:.6f} rad",
        "pose cov diag    " + ", ".join(f"{v:.6g}" for v in np.diagonal(ekf.pose_cov)),
    ]
    true_poses = result.extras.get("true_poses")
    if true_poses is not None:
        tx, ty, tt = true_poses[result.steps]
        heading_error = wrap_angle(theta - tt)
        lines.append(
            f"true pose        x = {tx:.6f} m, y = {ty:.6f} m, theta = {tt:.6f} rad "
            f"(error {math.hypot(x - tx, y - ty):.4f} m, {abs(heading_error):.4f} rad)"
        )
    lines.append(f"log det Sigma    {ekf.log_det:.6f}")
    truth = world.as_dict() if world is not None else {}
    lines.append("landmarks        id: estimate" + ("  [truth]  error" if truth else ""))
    for i, (lx, ly) in sorted(result.landmark_estimates().items()):
        line = f"  {i:>4}: ({lx:9.5f}, {ly:9.5f})"
        if i in truth:
            tx, ty = truth[i]
            line += f"  [{tx:9.5f}, {ty:9.5f}]  {math.hypot(lx - tx, ly - ty):.4f} m"
        lines.append(line)
    rmse = map_rmse(result, world)
    if rmse is not None:
        lines.append(f"map RMSE vs world: {rmse:.4f} m over {len(map_errors(result, world))} landmarks")
    return "\n".join(lines)


def _parser() -> argparse.ArgumentParser:
    parser = command_parser(
        "replay",
        description="Replay a drive through EKF-SLAM with the course's parameters. Without --data it replays "
        "the project's simulated drive (seeded by --seed).",
    )
    parser.add_argument("--data", type=Path, metavar="PATH", help="a sensor_data.dat file (course format)")
    parser.add_argument(
        "--world", type=Path, metavar="PATH", help="its world.dat (true landmarks; sets the landmark slots)"
    )
    parser.add_argument(
        "--seed", type=int, metavar="S", help="seed of the simulated drive (default 0; not with --data)"
    )
    parser.add_argument(
        "--steps", type=int, metavar="N", help="replay only the first N steps (default: every block)"
    )
    parser.add_argument("--sequential", action="store_true", help="one update per reading instead of a batch")
    parser.add_argument(
        "--init",
        choices=INIT_MODES,
        default=COURSE_SETTINGS.init_mode,
        help="landmark initialisation (default course)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object to stdout, nothing else")
    add_real_data_arguments(parser)
    parser.add_argument("--save-state", type=Path, metavar="FILE.npz", help="write mean, cov and log_det")
    parser.add_argument("--plot", type=Path, metavar="FILE.png", help="draw the final belief")
    parser.add_argument("--gif", type=Path, metavar="FILE.gif", help="animate the belief over the drive")
    parser.add_argument(
        "--tum",
        type=Path,
        metavar="FILE",
        help="write the estimated trajectory as a TUM file for evo (t = step s) and, for the simulated drive, "
        "the true one as <stem>_true<suffix>; course files (--data) have no true trajectory, so only the "
        "estimate is written",
    )
    return parser


def _check_output(parser: argparse.ArgumentParser, path: Path | None, suffix: str, option: str) -> None:
    if path is None:
        return
    if path.suffix.lower() != suffix:
        parser.error(f"{option} needs a {suffix} file name, got {path}")
    if not path.parent.is_dir():
        parser.error(f"{option}: directory {path.parent} does not exist")


@command_line("replay")
def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point; returns the exit status (usage errors exit 2 through ``parser.error``)."""
    parser = _parser()
    args = parser.parse_args(argv)
    if resolve_dataset(parser, args) != "course":
        return replay_real_data(parser, args)
    if args.world is not None and args.data is None:
        parser.error("--world needs --data (the simulated drive brings its own world)")
    if args.seed is not None and args.data is not None:
        parser.error("--seed applies to the simulated drive only, not to --data")
    if args.steps is not None and args.steps <= 0:
        parser.error(f"--steps must be a positive number of steps, got {args.steps}")
    _check_output(parser, args.save_state, ".npz", "--save-state")
    _check_output(parser, args.plot, ".png", "--plot")
    _check_output(parser, args.gif, ".gif", "--gif")
    if args.tum is not None and not args.tum.parent.is_dir():
        parser.error(f"--tum: directory {args.tum.parent} does not exist")
    if args.plot is not None or args.gif is not None:
        try:
            import matplotlib  # noqa: F401

            if args.gif is not None:
                import imageio  # noqa: F401
        except ImportError as error:
            parser.error(f"--plot/--gif need the render extra (pip install 'ekfslam-gym[render]'): {error}")

    from ..data.course import read_sensor_data, read_world
    from ..filter import FilterDivergedError
    from ..replay.course import landmark_labels, replay, summary

    true_poses = None
    if args.data is None:
        from ..data.synthetic import simulate_drive

        seed = 0 if args.seed is None else args.seed
        drive = simulate_drive(seed)
        data, world, true_poses = drive.data, drive.world, drive.poses
        source = f"the simulated drive (seed {seed})"
    else:
        for path in (args.data, args.world):
            if path is not None and not path.is_file():
                parser.error(f"no such file: {path}")
        try:  # the files' own errors name them and the line; an id outside the world file names the ids
            data = read_sensor_data(args.data)
            world = read_world(args.world) if args.world is not None else None
            landmark_labels(data, world)
        except (OSError, ValueError) as error:
            refuse(parser, "", error)
        source = str(args.data)
    if not len(data):
        parser.error(f"{source} has no ODOMETRY block")
    steps = len(data) if args.steps is None else args.steps
    if steps > len(data):
        parser.error(f"--steps {steps} but {source} has only {len(data)} steps")

    frame_every = math.ceil(steps / MAX_GIF_FRAMES) if args.gif is not None else 0
    try:
        result = replay(
            data,
            world=world,
            steps=steps,
            update="sequential" if args.sequential else "batch",
            init_mode=args.init,
            true_poses=true_poses,
            frame_every=frame_every,
        )
    except FilterDivergedError as error:
        print(f"error: the filter diverged: {error}", file=sys.stderr)
        return 1

    written = _write_outputs(args, result, world)
    if args.json:
        print(json.dumps(summary(result), allow_nan=False))
        for line in written:
            print(line, file=sys.stderr)
    else:
        print(_report(result, world, source, data.head(steps).n_readings))
        for line in written:
            print(line)
    return 0


def _write_outputs(args: argparse.Namespace, result: Replay, world: LandmarkMap | None) -> list[str]:
    written = []
    if args.save_state is not None:
        import numpy as np

        np.savez(
            args.save_state,
            mean=np.asarray(result.ekf.mean),
            cov=np.asarray(result.ekf.cov),
            log_det=np.float64(result.ekf.log_det),
            landmark_ids=result.labels,
            observed=np.asarray(result.ekf.observed),
        )
        written.append(f"wrote state to {args.save_state}")
    if args.plot is not None or args.gif is not None:
        from ..evaluation import plotting
        from ..replay.course import final_frame

        if args.plot is not None:
            plotting.save_png(args.plot, final_frame(result), world)
            written.append(f"wrote picture to {args.plot}")
        if args.gif is not None:
            frames = result.extras["frames"]
            plotting.save_gif(args.gif, frames, world)
            written.append(f"wrote animation ({len(frames)} frames) to {args.gif}")
    if args.tum is not None:
        from ..replay.course import export_tum, true_path_name

        paths = export_tum(result, args.tum)
        truth = f", the true one to {true_path_name(args.tum)}" if len(paths) > 1 else " (no true trajectory)"
        written.append(f"wrote the estimated trajectory (TUM) to {args.tum}{truth}")
    return written


if __name__ == "__main__":
    raise SystemExit(main())
