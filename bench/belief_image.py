"""Benchmark: what the belief image (``observation.belief_image``) costs, in env steps/s of EKFSLAM-v0.

    OPENBLAS_NUM_THREADS=1 python bench/belief_image.py [--steps 5000] [--repeats 5]

Three observations, alternated within each repeat so that other jobs on a shared machine slow them alike: the
default flat box, the Dict of the same parts, and the Dict with the belief image (16 x 16 cells, 3 channels,
and the wall memory marked every control step). One process, velocity actions drawn beforehand, resets
included; the median of ``--repeats`` runs by wall time and by process CPU time, printed as ratios to the Dict
without the image (its only difference).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from env import steps_per_second  # noqa: E402  (bench/env.py, beside this script)

from ekfslam_gym.envs import EKFSLAMEnv  # noqa: E402

VARIANTS = {
    "box": {},
    "dict": {"kind": "dict"},
    "dict + belief_image": {"kind": "dict", "belief_image": True},
}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: a check that the script runs")
    args = parser.parse_args(argv)
    if args.smoke:
        args.steps, args.repeats = 200, 1
    actions = np.random.default_rng(0).uniform(-1, 1, (args.steps, 2)).astype(np.float32)
    envs = {name: EKFSLAMEnv(observation=observation) for name, observation in VARIANTS.items()}
    for env in envs.values():  # compile and warm up outside the timing
        steps_per_second(env, actions[:50], clock=time.perf_counter)
    results = {name: {"wall": [], "cpu": []} for name in envs}
    for _ in range(args.repeats):
        for name, env in envs.items():
            results[name]["wall"].append(steps_per_second(env, actions, clock=time.perf_counter))
            results[name]["cpu"].append(steps_per_second(env, actions, clock=time.process_time))
    base = {clock: statistics.median(results["dict"][clock]) for clock in ("wall", "cpu")}
    print(
        f"EKFSLAM-v0, {args.steps} steps x {args.repeats} repeats (median), ratio to the Dict without the image"
    )
    print(f"{'observation':22s} {'steps/s wall':>13s} {'ratio':>6s} {'steps/s cpu':>12s} {'ratio':>6s}")
    for name in envs:
        wall = statistics.median(results[name]["wall"])
        cpu = statistics.median(results[name]["cpu"])
        print(f"{name:22s} {wall:13,.0f} {wall / base['wall']:6.3f} {cpu:12,.0f} {cpu / base['cpu']:6.3f}")


if __name__ == "__main__":
    main()
