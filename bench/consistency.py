"""Filter consistency under the ways a policy drives: pose ANEES per step over seeded Monte-Carlo runs of the env.

    OPENBLAS_NUM_THREADS=1 python bench/consistency.py [--runs 50] [--steps 200] [--preset EKFSLAM-v0]
        [--drivings forward,random,spin,turn,held,circle] [--variants ekf,fej,iekf] [--models odometry,wheels]
        [--smoke]

Each run is an episode of the preset (``gym.make``, its ``filter`` section set to the odometry model and the
variant), reset with the run's seed and stepped with the driving's actions (``ekfslam_gym.evaluation.drivings``):
the env's own reset and step, nothing re-implemented. The env's ``info["pose_nees"]`` (e^T Sigma_xx^-1 e, e the
true pose minus the estimate, heading wrapped) is averaged over the runs (ANEES); a consistent filter's ANEES
lies in the two-sided 95 % chi-square bounds for 3 dof and M runs at about 95 % of the steps (Bar-Shalom, Li &
Kirubarajan, *Estimation with Applications to Tracking and Navigation*, section 5.4). Printed per (driving,
odometry model, variant): the median ANEES over the steps and the share of steps inside the bounds, plus the
share of steps in contact with a wall (``info["collision"]``) and the number of runs whose filter failed
numerically (a NaN NEES).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402

import ekfslam_gym  # noqa: E402, F401  (registers the ids)
from ekfslam_gym.envs.presets import PRESETS  # noqa: E402
from ekfslam_gym.evaluation.drivings import DRIVINGS, driving_actions  # noqa: E402
from ekfslam_gym.evaluation.metrics import nees_bounds  # noqa: E402
from ekfslam_gym.filter.settings import VARIANTS  # noqa: E402

MODELS = ("odometry", "wheels")


@dataclass
class Consistency:
    """Pose NEES (runs, steps) of one (driving, odometry model, variant), NaN after an episode's end or a
    numerical failure, and whether each step touched a wall."""

    nees: np.ndarray
    contact: np.ndarray

    @property
    def anees(self) -> np.ndarray:
        """ANEES per step: the mean over the runs that reached it."""
        with warnings.catch_warnings():  # a step no run reached is NaN, not a warning
            warnings.simplefilter("ignore", RuntimeWarning)
            return np.nanmean(self.nees, axis=0)

    def inside(self, bounds: tuple[float, float]) -> float:
        """Share of the steps whose ANEES lies inside ``bounds``."""
        anees = self.anees
        return float(np.mean((anees >= bounds[0]) & (anees <= bounds[1])))

    @property
    def failed(self) -> int:
        """Runs whose filter failed numerically (a NaN NEES while the episode went on)."""
        return int(np.isnan(self.nees).any(axis=1).sum())


def pose_nees(
    preset: str,
    driving: str,
    model: str,
    variant: str,
    runs: int,
    steps: int,
    pose_prior: float | None = None,
) -> Consistency:
    """Seeded runs 0..runs-1 of ``preset`` driven by ``driving`` for ``steps`` control steps, the filter set to
    ``model`` odometry and ``variant`` (and ``pose_prior`` when given)."""
    section = {"motion_model": model, "variant": variant}
    if pose_prior is not None:
        section["pose_prior"] = pose_prior
    env = gym.make(preset, max_episode_steps=steps, filter=section, action={"kind": "velocity", "hold": 1})
    robot = env.unwrapped.config.robot
    nees = np.full((runs, steps), np.nan)
    contact = np.zeros((runs, steps), dtype=bool)
    for run in range(runs):
        env.reset(seed=run)
        for t, action in enumerate(driving_actions(driving, np.random.default_rng([run, 0]), steps, robot)):
            _, _, terminated, truncated, info = env.step(action.astype(np.float32))
            nees[run, t], contact[run, t] = info["pose_nees"], info["collision"]
            if terminated or truncated:
                break
    env.close()
    return Consistency(nees, contact)


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
    bounds = nees_bounds(3, args.runs)
    combos = [(m, v) for m in args.models.split(",") for v in args.variants.split(",")]
    prior = "the preset's" if args.pose_prior is None else f"{args.pose_prior:g}"
    print(f"{args.preset}: {args.runs} runs x {args.steps} steps, filter.pose_prior {prior}; "
          f"95 % bounds of the ANEES [{bounds[0]:.2f}, {bounds[1]:.2f}]")  # fmt: skip
    print("| driving | odometry | variant | median ANEES | steps inside | contact steps | failed |")
    print("|---|---|---|---:|---:|---:|---:|")
    start = time.perf_counter()
    for driving in args.drivings.split(","):
        for model, variant in combos:
            found = pose_nees(args.preset, driving, model, variant, args.runs, args.steps, args.pose_prior)
            print(f"| {driving} | {model} | {variant} | {np.nanmedian(found.anees):.2f} | "
                  f"{found.inside(bounds):.0%} | {found.contact.mean():.1%} | {found.failed} |")  # fmt: skip
    print(f"({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
