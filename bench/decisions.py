"""Benchmark: mean wall-clock time of one ``act()`` call (one decision) of the scripted agents in EKFSLAM-v0.

    OPENBLAS_NUM_THREADS=1 python bench/decisions.py [--agents frontier,greedy,greedy2,lawnmower,circle] [--seeds 3]
        [--steps 200] [--env-id EKFSLAM-v0] [--smoke]

Each agent drives ``--seeds`` seeded episodes of ``--steps`` steps; only its ``act()`` calls are timed (the env's
steps and the agent's ``reset`` are not). A first, untimed episode warms up numba's compiled kernels, so the
figures are the steady cost per decision, not the compilation. The last column is each agent's mean over the
first agent's.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402
from ekfslam_gym.agents import make_agent  # noqa: E402

import ekfslam_gym  # noqa: E402, F401


def run(agent, env, seed: int, steps: int) -> list[float]:
    """One seeded episode of up to ``steps`` steps; the seconds each ``act()`` call took."""
    observation, _ = env.reset(seed=seed)
    agent.reset(env, seed=seed)
    times = []
    for _ in range(steps):
        start = time.perf_counter()
        action = agent.act(observation)
        times.append(time.perf_counter() - start)
        observation, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    return times


def act_times(name: str, env_id: str, seeds: int, steps: int) -> np.ndarray:
    """Seconds per ``act()`` call of agent ``name`` over seeds 0..seeds-1, after an untimed warm-up episode."""
    env = gym.make(env_id, max_episode_steps=steps)
    agent = make_agent(name)
    run(agent, env, 0, steps)  # compiles numba kernels on first use
    times = [t for seed in range(seeds) for t in run(agent, env, seed, steps)]
    env.close()
    return np.array(times)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--agents", default="frontier,greedy,greedy2,lawnmower,circle")
    parser.add_argument("--env-id", default="EKFSLAM-v0")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: a check that the script runs")
    args = parser.parse_args(argv)
    if args.smoke:
        args.seeds, args.steps = 1, 20
    print(f"{args.env_id}: {args.seeds} seeds x {args.steps} steps, time per act() call")
    print(f"{'agent':<10} {'mean µs':>9} {'median µs':>10} {'p99 µs':>9} {'calls/s':>9} {'mean / first':>13}")
    first = None
    for name in args.agents.split(","):
        t = act_times(name.strip(), args.env_id, args.seeds, args.steps) * 1e6
        first = t.mean() if first is None else first
        print(
            f"{name:<10} {t.mean():9.1f} {np.median(t):10.1f} {np.percentile(t, 99):9.1f} {1e6 / t.mean():9.0f}"
            f" {t.mean() / first:13.2f}"
        )


if __name__ == "__main__":
    main()
