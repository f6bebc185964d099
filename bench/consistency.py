"""Filter consistency under the ways a policy drives: pose ANEES per step over seeded Monte-Carlo runs.

    OPENBLAS_NUM_THREADS=1 python bench/consistency.py [--runs 50] [--steps 200] [--preset EKFSLAM-v0]
        [--drivings forward,random,spin,turn,held,circle] [--variants ekf,fej,iekf] [--models odometry,wheels]
        [--smoke]

Each run builds the preset's layout and ``World`` and drives it the way ``EKFSLAMEnv.reset/step`` does (the
first reading corrects the filter at the start pose; then per step: the clipped action scaled by v_max and
omega_max, the odometry, the readings, ``predict(u, control_cov=M)`` and ``correct``). One simulated run feeds
every (variant, odometry model) filter: the world and its readings do not depend on the filter, and each
odometry model draws its noise from its own seeded generator. The pose NEES of step t, e^T Sigma_xx^-1 e with e
the true pose minus the estimate (heading wrapped), is averaged over the runs (ANEES); a consistent filter's
ANEES lies in the two-sided 95 % chi-square bounds for 3 dof and M runs at about 95 % of the steps (Bar-Shalom,
Li & Kirubarajan, *Estimation with Applications to Tracking and Navigation*, section 5.4). Printed per (driving,
odometry model, variant): the median ANEES over the steps and the share of steps inside the bounds, plus the
share of steps in contact with a wall and the number of filters that failed numerically.

Drivings: ``ekfslam_gym.evaluation.drivings``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from ekfslam_gym.envs.config import EnvConfig  # noqa: E402
from ekfslam_gym.envs.presets import PRESETS  # noqa: E402
from ekfslam_gym.evaluation.drivings import DRIVINGS, driving_actions  # noqa: E402
from ekfslam_gym.filter import EKFSLAM, FilterDivergedError  # noqa: E402
from ekfslam_gym.filter.settings import VARIANTS  # noqa: E402
from ekfslam_gym.sim import WheelOdometryNoise, World, make_layout  # noqa: E402

MODELS = ("odometry", "wheels")


@dataclass
class Run:
    """One simulated run: what every filter is fed, and the truth to score it against."""

    layout_start: np.ndarray
    n_landmarks: int
    first_readings: tuple[np.ndarray, np.ndarray]
    readings: list[tuple[np.ndarray, np.ndarray]]
    odometry: dict[str, list[tuple[np.ndarray, np.ndarray]]]  # model -> per step (u, M)
    true_poses: np.ndarray  # (steps, 3), after each step
    contact: np.ndarray  # (steps,) bool


def simulate(config: EnvConfig, driving: str, seed: int, steps: int, wheels: WheelOdometryNoise) -> Run:
    """The env's reset and steps without the filter (the world never depends on it)."""
    rng = np.random.default_rng(seed)
    odometry_rngs = {model: np.random.default_rng([seed, k + 1]) for k, model in enumerate(MODELS)}
    layout = make_layout(
        config.world.layout, rng, config.world.n_landmarks,
        robot_radius=config.robot.radius, **config.world.layout_kwargs,
    )  # fmt: skip
    world = World(layout, config.robot, config.sensor, config.odometry, None, config.dt, config.substeps,
                  wheel_noise=wheels)  # fmt: skip
    first = world.sense(rng)
    run = Run(layout.start, layout.n_landmarks, (first.ids, first.z), [], {m: [] for m in MODELS},
              np.empty((steps, 3)), np.zeros(steps, dtype=bool))  # fmt: skip
    robot = config.robot
    for t, (a0, a1) in enumerate(driving_actions(driving, np.random.default_rng([seed, 0]), steps, robot)):
        run.contact[t] = world.step(a0 * robot.v_max, a1 * robot.omega_max)
        reading = world.odometry(odometry_rngs["odometry"])
        run.odometry["odometry"].append((reading.u, reading.cov))
        reading = world.wheel_odometry(odometry_rngs["wheels"])
        run.odometry["wheels"].append((reading.u, reading.cov))
        sensed = world.sense(rng)
        run.readings.append((sensed.ids, sensed.z))
        run.true_poses[t] = world.pose
    return run


def pose_nees(run: Run, config: EnvConfig, model: str, variant: str, wheel_base: float) -> np.ndarray:
    """Pose NEES per step of one filter on one run (NaN from a numerical failure on)."""
    ekf = EKFSLAM(
        run.n_landmarks, config.filter, motion_model=model, variant=variant, dt=config.dt,
        measurement_noise=config.sensor.cov, initial_pose=run.layout_start,
        min_range=max(config.sensor.min_range, 1e-3), wheel_base=wheel_base,
    )  # fmt: skip
    ekf.correct(*run.first_readings)
    nees = np.full(len(run.readings), np.nan)
    for t, ((u, cov), (ids, z)) in enumerate(zip(run.odometry[model], run.readings)):
        try:
            ekf.predict(u, control_cov=cov)
            ekf.correct(ids, z)
        except FilterDivergedError:
            break
        error = run.true_poses[t] - ekf.pose
        error[2] = (error[2] + math.pi) % (2.0 * math.pi) - math.pi
        nees[t] = error @ np.linalg.solve(ekf.pose_cov, error)
    return nees


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--runs", type=int, default=50)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--preset", default="EKFSLAM-v0", choices=sorted(PRESETS))
    parser.add_argument("--drivings", default=",".join(DRIVINGS))
    parser.add_argument("--variants", default=",".join(VARIANTS))
    parser.add_argument("--models", default=",".join(MODELS))
    parser.add_argument(
        "--pose-prior", type=float, default=None, help="filter.pose_prior (default the preset's)"
    )
    parser.add_argument(
        "--smoke", action="store_true", help="2 runs of 20 steps: a check that the script runs"
    )
    args = parser.parse_args(argv)
    if args.smoke:
        args.runs, args.steps = 2, 20
    config = EnvConfig.from_overrides(**PRESETS[args.preset])
    if args.pose_prior is not None:
        config = EnvConfig.from_overrides(config, filter={"pose_prior": args.pose_prior})
    wheels = WheelOdometryNoise()
    low, high = stats.chi2.ppf([0.025, 0.975], 3 * args.runs) / args.runs
    combos = [(m, v) for m in args.models.split(",") for v in args.variants.split(",")]
    print(f"{args.preset}: {args.runs} runs x {args.steps} steps, filter.pose_prior {config.filter.pose_prior:g}; "
          f"95 % bounds of the ANEES [{low:.2f}, {high:.2f}]")  # fmt: skip
    print(f"{wheels}")
    print("| driving | odometry | variant | median ANEES | steps inside | contact steps | failed |")
    print("|---|---|---|---:|---:|---:|---:|")
    start = time.perf_counter()
    for driving in args.drivings.split(","):
        nees = {combo: np.empty((args.runs, args.steps)) for combo in combos}
        contact = np.empty((args.runs, args.steps), dtype=bool)
        for r in range(args.runs):
            run = simulate(config, driving, r, args.steps, wheels)
            contact[r] = run.contact
            for model, variant in combos:
                nees[model, variant][r] = pose_nees(run, config, model, variant, wheels.wheel_base)
        for model, variant in combos:
            values = nees[model, variant]
            failed = int(np.isnan(values).any(axis=1).sum())
            anees = np.nanmean(values, axis=0)
            inside = np.mean((anees >= low) & (anees <= high))
            print(f"| {driving} | {model} | {variant} | {np.median(anees):.2f} | {inside:.0%} | "
                  f"{contact.mean():.1%} | {failed} |")  # fmt: skip
    print(f"({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
