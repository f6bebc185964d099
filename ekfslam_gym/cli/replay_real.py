"""``ekfslam-replay`` on a real robot's data set: its options, and the checks of what applies to which data set.

``--dataset mrclam`` (or ``--data`` naming a folder that holds ``Barcodes.dat``): UTIAS MRCLAM robot 1, replayed
with the velocity model (``ekfslam_gym.replay.mrclam``): ``--noise textbook`` (the default: range 0.15 m, bearing
0.08 rad) or ``--noise fitted`` (maximum likelihood on this drive, ``FITTED_MRCLAM``). ``--dataset gtsam``: a
GTSAM 2-D file whose odometry is one chain (Victoria Park). The report lists NIS against its chi^2 band (real
data has no pose truth), the filter's time per step, for MRCLAM each landmark's error after the best SE(2)
alignment to the survey and, with ``--association nearest|jcbc`` (barcodes hidden), the false and missed
associations counted against the barcodes. ``--smoother`` adds the full-SLAM smoother of the same data: its chi^2
and its trajectory's distance to the filter's. The replay and its figures are ``ekfslam_gym.replay.real``'s.
"""

from __future__ import annotations

import argparse
import json

from ..filter.settings import ASSOCIATIONS, VARIANTS
from ..replay.formats import DATASETS, detect_dataset
from .common import refuse

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
    dataset = args.dataset = args.dataset if args.dataset is not None else detect_dataset(args.data)
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


def replay_real_data(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """Replay a real data set (``ekfslam_gym.replay.real``) and print its report (or one JSON object with
    ``--json``); a data set that cannot be read is the user's input, named with its flag."""
    from ..evaluation.report import json_safe
    from ..replay import real

    if args.team and args.dataset == "mrclam":
        from .replay_team import replay_team_data

        return replay_team_data(parser, args)
    if args.dataset == "gtsam":
        from ..data.gtsam2d import read_gtsam2d
        from ..replay.chain import check_chain

        try:
            dataset = read_gtsam2d(args.data)
            check_chain(dataset)
        except (OSError, ValueError) as error:  # the file's own errors name it and the line
            refuse(parser, "--data", error)
        run = real.replay_gtsam(dataset, args.variant or "ekf", smoother=args.smoother)
    else:
        from ..data.mrclam import load_mrclam
        from ..replay.mrclam import FITTED_MRCLAM, ReplaySettings

        try:
            recording = load_mrclam(args.data)
        except (OSError, ValueError) as error:
            refuse(parser, "--data", error)
        settings = (FITTED_MRCLAM if args.noise == "fitted" else ReplaySettings()).choosing(
            variant=args.variant, association=args.association
        )
        run = real.replay_mrclam(recording, settings, robots=args.robots, smoother=args.smoother)
    if args.plot is not None:
        run.save_picture(args.plot)
    if args.json:
        print(json.dumps(json_safe(run.figures), allow_nan=False))
    else:
        print(real.text_report(run.figures, args.data))
    return 0
