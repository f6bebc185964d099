"""Benchmark: unknown data association in EKFSLAM-v0, nearest neighbour against JCBC.

    OPENBLAS_NUM_THREADS=1 python bench/association.py [--episodes 10] [--steps 500] [--repeats 3]

(a) False and missed associations (``info["false_associations"]``, ``info["missed_associations"]``) over
seeded episodes with ``sensor.clutter_rate`` 0.5 and ``sensor.detection_prob`` 0.9, every method under the same
drive (seeded random actions, each held 10 steps) and the same readings (the world's random draws do not
depend on the filter). (b) Env steps/s at 30 landmarks, association ``known`` against ``jcbc`` (and
``nearest``), alternated, the median of ``--repeats`` runs; printed as ratios to ``known``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from ekfslam_gym.envs import EKFSLAMEnv  # noqa: E402

CLUTTER = {"clutter_rate": 0.5, "detection_prob": 0.9}


def held_actions(seed: int, steps: int, hold: int = 10) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.repeat(rng.uniform(-1, 1, (-(-steps // hold), 2)), hold, axis=0)[:steps].astype(np.float32)


def episode(association: str, seed: int, steps: int) -> dict[str, float]:
    env = EKFSLAMEnv(filter={"association": association}, sensor=CLUTTER, max_episode_steps=steps)
    env.reset(seed=seed)
    info = {}
    for action in held_actions(seed, steps):
        _, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    return {
        "false": info["false_associations"],
        "missed": info["missed_associations"],
        "rmse": info["map_rmse"],
        "seen": info["landmarks_seen"],
    }


def steps_per_second(association: str, sensor: dict, steps: int) -> float:
    env = EKFSLAMEnv(
        filter={"association": association}, sensor=sensor, max_episode_steps=10**9, done_std=0.0
    )
    actions = held_actions(1, steps)
    env.reset(seed=0)
    for action in actions[:200]:  # warm up (JIT compilation when the AOT kernels are absent)
        env.step(action)
    env.reset(seed=0)
    start = time.perf_counter()
    for action in actions:
        env.step(action)
    return steps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--steps", type=int, default=500)
    parser.add_argument("--speed-steps", type=int, default=5000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: a check that the script runs")
    args = parser.parse_args()
    if args.smoke:
        args.episodes, args.steps, args.speed_steps, args.repeats = 2, 60, 300, 1

    print(
        f"(a) clutter_rate 0.5, detection_prob 0.9, {args.episodes} episodes x {args.steps} steps of EKFSLAM-v0"
    )
    print(f"{'association':<12}{'false':>8}{'missed':>8}{'map RMSE m':>12}{'landmarks held':>16}")
    totals = {}
    for method in ("nearest", "jcbc"):
        runs = [episode(method, seed, args.steps) for seed in range(args.episodes)]
        totals[method] = (sum(r["false"] for r in runs), sum(r["missed"] for r in runs))
        print(
            f"{method:<12}{totals[method][0]:>8}{totals[method][1]:>8}"
            f"{statistics.median(r['rmse'] for r in runs):>12.3f}{statistics.median(r['seen'] for r in runs):>16}"
        )
    false_n, false_j = totals["nearest"][0], totals["jcbc"][0]
    print(f"false associations jcbc / nearest: {false_j} / {false_n} = {false_j / max(false_n, 1):.2f}")

    print(
        f"\n(b) env steps/s at 30 landmarks, median of {args.repeats} alternated runs of {args.speed_steps} steps"
    )
    for label, sensor in (("default sensor", {}), ("clutter 0.5, detection 0.9", CLUTTER)):
        rates: dict[str, list[float]] = {m: [] for m in ("known", "nearest", "jcbc")}
        for _ in range(args.repeats):
            for method in rates:
                rates[method].append(steps_per_second(method, sensor, args.speed_steps))
        known = statistics.median(rates["known"])
        cells = ", ".join(f"{m} {statistics.median(r):,.0f}" for m, r in rates.items())
        ratios = ", ".join(
            f"{m} / known {statistics.median(rates[m]) / known:.2f}" for m in ("nearest", "jcbc")
        )
        print(f"{label}: {cells} steps/s; {ratios}")


if __name__ == "__main__":
    main()
