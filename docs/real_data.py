"""Draw the pictures and print the tables of docs/real-data.md (the filter on MRCLAM robot 1 and Victoria Park).

    python docs/real_data.py [--data ../shared/data/mrclam] [--zero-shot DIR]

Writes docs/real_data_mrclam_{map,nis}.png and, where Victoria Park's file is (``--victoria-park``),
docs/real_data_victoria_park_{map,nis}.png, and prints the Markdown tables. With
``--zero-shot DIR`` it also prints the zero-shot table from the ``ekfslam-evaluate --json`` outputs in DIR
(``mrclam_ppo.json``, ``mrclam_base.json``, ``default_ppo.json``, ``default_base.json``; commands on the page).
"""

from __future__ import annotations

import argparse
import json
import platform
from pathlib import Path

import numpy as np

from ekfslam_gym.data.gtsam2d import read_gtsam2d
from ekfslam_gym.data.mrclam import load_mrclam
from ekfslam_gym.evaluation.alignment import align_se2
from ekfslam_gym.graph.optimizer import GTSAM_LM, optimize
from ekfslam_gym.replay.chain import anchored_at_first_pose, replay_chain
from ekfslam_gym.replay.figures import nis_summary, summarise
from ekfslam_gym.replay.mrclam import (
    FITTED_MRCLAM,
    ReplaySettings,
    build_drive,
    landmark_errors,
    replay_drive,
)
from ekfslam_gym.replay.pictures import save_map_picture, save_nis_picture, save_trajectory_picture
from ekfslam_gym.replay.smoother import smooth_keyframes

DOCS = Path(__file__).resolve().parent


def _row(name: str, figures: dict) -> str:
    nis = figures["nis"]
    return (
        f"| {name} | {figures['median_error']:.3f} | {figures['within_0.18']} / {figures['landmarks_mapped']} | "
        f"{nis['mean']:.2f} | {100 * nis['inside']:.0f} % | {100 * nis['windows_inside']:.0f} % | "
        f"{figures['microseconds_per_step']:.0f} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--data", type=Path, default=DOCS.parents[1] / "shared" / "data" / "mrclam")
    parser.add_argument("--zero-shot", type=Path, default=None)
    parser.add_argument(
        "--victoria-park",
        type=Path,
        default=DOCS.parents[1] / "shared" / "data" / "victoria_park" / "victoria_park.txt",
    )
    args = parser.parse_args()
    run = load_mrclam(args.data)
    ids, xy = run.landmarks.ids, run.landmarks.positions
    drive = build_drive(run)
    textbook = ReplaySettings()

    print(f"machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}\n")
    print(
        "| filter | median error [m] | within 0.18 m | mean NIS | NIS inside 95 % | 50-means inside | us / step |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|")
    runs = {}
    for name, settings in [
        ("ekf, textbook noise", textbook),
        ("fej, textbook noise", textbook.choosing(variant="fej")),
        ("iekf, textbook noise", textbook.choosing(variant="iekf")),
        ("ekf, fitted noise", FITTED_MRCLAM),
        ("fej, fitted noise", FITTED_MRCLAM.choosing(variant="fej")),
        ("iekf, fitted noise", FITTED_MRCLAM.choosing(variant="iekf")),
    ]:
        runs[name] = replay_drive(drive, ids, settings)
        print(_row(name, summarise(runs[name], settings, ids, xy)))

    base = runs["ekf, textbook noise"]
    fitted = summarise(runs["ekf, fitted noise"], FITTED_MRCLAM, ids, xy)
    errors, transform = landmark_errors(base.landmark_estimates(), ids, xy)
    smoothing = smooth_keyframes(drive, ids, textbook, base.poses)
    smoothed = {int(i): p for i, p in zip(ids, smoothing.landmarks)}
    smoother_errors, _ = landmark_errors(smoothed, ids, xy)
    print(
        "\n| landmark (subject) | barcode | readings | ekf, textbook [m] | ekf, fitted [m] | smoother [m] |"
    )
    print("|---:|---:|---:|---:|---:|---:|")
    counts = dict(zip(*np.unique(drive.subject, return_counts=True), strict=True))
    for i in ids.tolist():
        print(
            f"| {i} | {run.barcodes[i]} | {counts.get(i, 0)} | {errors[i]:.3f} | "
            f"{fitted['landmark_errors'][str(i)]:.3f} | {smoother_errors[i]:.3f} |"
        )
    # the two far-off landmarks: is each estimate at the other's surveyed place?
    moved = {i: transform.points(p[None])[0] for i, p in base.landmark_estimates().items()}
    truth = dict(zip(ids.tolist(), xy))
    far = [i for i, e in errors.items() if e > 1.0]
    for i in far:
        nearest = min(truth, key=lambda j: np.hypot(*(moved[i] - truth[j])))
        print(
            f"\nlandmark {i}: estimate {np.hypot(*(moved[i] - truth[nearest])):.3f} m from subject {nearest}'s survey"
        )
    swapped = {i: j for i, j in zip(far, far[::-1])}
    fixed = {swapped.get(i, i): p for i, p in base.landmark_estimates().items()}
    fixed_errors, _ = landmark_errors(fixed, ids, xy)
    values = np.array(list(fixed_errors.values()))
    print(
        f"with subjects {far} swapped: median {np.median(values):.3f} m, {np.sum(values <= 0.18)} of 15 within "
        f"0.18 m, max {values.max():.3f} m"
    )

    gap = np.hypot(*(smoothing.poses[:, :2] - base.poses[smoothing.keyframes + 1, :2]).T)
    print(
        f"\nsmoother: {len(smoothing.keyframes)} poses, chi2 {smoothing.chi2:.1f} for {smoothing.dof} dof, "
        f"{smoothing.result.iterations} LM iterations, {smoothing.result.seconds:.1f} s; trajectory vs the filter "
        f"{np.sqrt(np.mean(gap**2)):.3f} m rms, {gap.max():.3f} m max; landmarks median "
        f"{np.median(list(smoother_errors.values())):.3f} m"
    )

    print(
        "\n| association | noise | readings | median error [m] | within 0.18 m | false | missed | started | mean NIS |"
    )
    print("|---|---|---|---:|---:|---:|---:|---:|---:|")
    with_robots = build_drive(run, robots=True)
    for association in ("nearest", "jcbc"):
        for noise_name, noise in (("textbook", textbook), ("fitted", FITTED_MRCLAM)):
            for readings_name, source in (("landmarks", drive), ("+ robots", with_robots)):
                settings = noise.choosing(association=association)
                f = summarise(replay_drive(source, ids, settings), settings, ids, xy)
                print(
                    f"| {association} | {noise_name} | {readings_name} ({len(source.z)}) | {f['median_error']:.3f} | "
                    f"{f['within_0.18']} / {f['landmarks_mapped']} | {f['false_associations']} | "
                    f"{f['missed_associations']} | {f['new_landmarks']} | {f['nis']['mean']:.2f} |"
                )

    save_map_picture(
        DOCS / "real_data_mrclam_map.png", base, transform, ids, xy, smoothing.poses,
        "MRCLAM robot 1: EKF (textbook noise, known barcodes) and the smoother, aligned to the survey",
    )  # fmt: skip
    save_nis_picture(
        DOCS / "real_data_mrclam_nis.png",
        {
            k: _minutes(runs[k], drive)
            for k in ("ekf, textbook noise", "ekf, fitted noise", "fej, fitted noise", "iekf, fitted noise")
        },
        title="MRCLAM robot 1: NIS of the re-observations (2 dof), means of 50",
    )
    print(f"\nwrote {DOCS / 'real_data_mrclam_map.png'} and {DOCS / 'real_data_mrclam_nis.png'}")
    if args.victoria_park.is_file():
        victoria_park(args.victoria_park)
    if args.zero_shot is not None:
        _zero_shot(args.zero_shot)


def _minutes(result, drive) -> tuple[np.ndarray, np.ndarray]:
    return (result.nis_at - drive.time[0]) / 60.0, result.nis


def victoria_park(path: Path) -> None:
    """The filter on Victoria Park (GTSAM's file), beside GTSAM-style LM on the same file."""
    dataset = read_gtsam2d(path)
    print("\n| Victoria Park filter | landmarks | mean NIS | NIS inside 95 % | 50-means inside | us / step |")
    print("|---|---:|---:|---:|---:|---:|")
    runs = {}
    for variant in ("ekf", "fej", "iekf"):
        runs[variant] = result = replay_chain(dataset, variant)
        nis = nis_summary(result.nis)
        print(
            f"| {variant} | {int(result.ekf.observed.sum())} | {nis['mean']:.2f} | {100 * nis['inside']:.0f} % | "
            f"{100 * nis['windows_inside']:.0f} % | {1e6 * result.seconds / result.steps:.0f} |"
        )
    problem = dataset.to_problem()
    smoothed = optimize(problem.graph, problem.initial, "lm", **GTSAM_LM)
    base = runs["ekf"]
    anchor = anchored_at_first_pose(smoothed.values.poses)
    smoothed_poses = anchor.poses(smoothed.values.poses)
    print(
        f"\nVictoria Park smoother (LM, GTSAM's settings): chi2 {smoothed.final_error:.0f}, {smoothed.iterations} "
        f"iterations, {smoothed.seconds:.1f} s"
    )
    for variant, result in runs.items():
        gap = np.hypot(*(smoothed_poses[:, :2] - result.poses[:, :2]).T)
        landmark_gap = np.hypot(*(anchor.points(smoothed.values.landmarks) - result.ekf.landmarks).T)
        best = align_se2(result.ekf.landmarks, smoothed.values.landmarks)
        aligned_gap = np.hypot(*(best.points(result.ekf.landmarks) - smoothed.values.landmarks).T)
        print(
            f"{variant} vs smoother (first poses together): trajectory {np.sqrt(np.mean(gap**2)):.1f} m rms, "
            f"{gap.max():.1f} m max; landmarks median {np.median(landmark_gap):.1f} m; after the best SE(2) "
            f"alignment of the maps: median {np.median(aligned_gap):.1f} m, max {aligned_gap.max():.1f} m"
        )
    save_trajectory_picture(
        DOCS / "real_data_victoria_park_map.png", base.poses, base.ekf.landmarks, base.ekf.landmark_covs(),
        smoothed=smoothed_poses, title="Victoria Park: EKF (file noise, known identities) and LM smoother",
        size=(6.4, 6.4),
    )  # fmt: skip
    save_nis_picture(
        DOCS / "real_data_victoria_park_nis.png",
        {k: (r.nis_pose, r.nis) for k, r in runs.items()},
        title="Victoria Park: NIS of the re-observations (2 dof), means of 50",
        xlabel="pose index",
    )


def _zero_shot(folder: Path) -> None:
    metrics = ("return", "landmark_rmse", "ate", "seen_fraction", "anees", "collisions")
    print("\n| world | agent | episodes | " + " | ".join(metrics) + " |")
    print("|---|---|---:|" + "---:|" * len(metrics))
    for world in ("mrclam", "default"):
        rows: dict[str, dict] = {}
        for part in ("base", "ppo"):
            path = folder / f"{world}_{part}.json"
            if not path.is_file():
                continue
            data = json.loads(path.read_text())
            for entry in [data] if "agent" in data else data.values():
                rows[entry["agent"]] = entry
        for agent, entry in rows.items():
            values = " | ".join(f"{entry['metrics'][m]['iqm']:.3g}" for m in metrics)
            print(f"| {world} | {agent} | {entry['episodes']} | {values} |")


if __name__ == "__main__":
    main()
