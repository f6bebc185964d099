"""Benchmark: team steps/s of the team env for 1, 3 and 5 robots with 30 and 120 landmarks, against the
single-robot env in the same run.

    OPENBLAS_NUM_THREADS=1 python bench/team.py [--steps 3000] [--robots 1 3 5] [--landmarks 30 120]

A team step is one control step of every robot (``action.hold`` 1: physics, every robot's odometry, landmark
and robot-to-robot readings, the joint filter's predictions and corrections, and every robot's observation and
info), with random primitives drawn beforehand, one process, no agent. The single-robot env steps the same
world (``EKFSLAMEnv`` with primitives held 1 step and the same landmarks). Rates are the best of three,
measured alternately by wall time and by this process's CPU time (which other jobs on a shared machine change
far less); the ratio is team steps/s over single-robot steps/s, and a robot-step's cost the team's CPU time per
step and robot over the single-robot env's per step.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from ekfslam_gym.envs import EKFSLAMEnv  # noqa: E402
from ekfslam_gym.multi import parallel_env  # noqa: E402


def settings(landmarks: int) -> dict:
    return {
        "world": {"n_landmarks": landmarks},
        "action": {"hold": 1},
        "max_episode_steps": 10**9,
        "done_std": 0.0,
    }


def single_rate(landmarks: int, actions: np.ndarray, clock) -> float:
    env = EKFSLAMEnv(preset=None, action={"kind": "primitives", "hold": 1}, **{
        k: v for k, v in settings(landmarks).items() if k != "action"
    })  # fmt: skip
    env.reset(seed=0)
    start = clock()
    for a in actions[:, 0]:
        env.step(a)
    return len(actions) / (clock() - start)


def team_rate(n_robots: int, landmarks: int, actions: np.ndarray, clock) -> float:
    team = parallel_env(n_robots=n_robots, **settings(landmarks))
    team.reset(seed=0)
    agents = team.possible_agents
    steps = [dict(zip(agents, row[:n_robots].tolist())) for row in actions]
    start = clock()
    for step in steps:
        team.step(step)
    return len(steps) / (clock() - start)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--robots", type=int, nargs="+", default=[1, 3, 5])
    parser.add_argument("--landmarks", type=int, nargs="+", default=[30, 120])
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: a check that the script runs")
    args = parser.parse_args(argv)
    if args.smoke:
        args.steps, args.robots, args.landmarks = 100, [1, 3], [30]
    actions = np.random.default_rng(0).integers(0, 9, (args.steps, max(args.robots)))
    print(f"OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}, {args.steps} random team steps each")
    print(
        f"{'landmarks':>9} {'robots':>6} | {'team steps/s':>12} {'CPU':>8} | {'single':>8} {'CPU':>8} | "
        f"{'ratio':>6} {'CPU':>6} | {'robot-step cost':>15}"
    )
    for landmarks in args.landmarks:
        team_rate(max(args.robots), landmarks, actions[:20], time.perf_counter)  # compile outside the timing
        single_rate(landmarks, actions[:20], time.perf_counter)
        for n_robots in args.robots:
            wall = cpu = single_wall = single_cpu = 0.0
            for _ in range(3):
                wall = max(wall, team_rate(n_robots, landmarks, actions, time.perf_counter))
                single_wall = max(single_wall, single_rate(landmarks, actions, time.perf_counter))
                cpu = max(cpu, team_rate(n_robots, landmarks, actions, time.process_time))
                single_cpu = max(single_cpu, single_rate(landmarks, actions, time.process_time))
            print(
                f"{landmarks:>9} {n_robots:>6} | {wall:>12,.0f} {cpu:>8,.0f} | {single_wall:>8,.0f} "
                f"{single_cpu:>8,.0f} | {wall / single_wall:>6.3f} {cpu / single_cpu:>6.3f} | "
                f"{single_cpu / (n_robots * cpu):>14.2f}x"
            )
    print(
        "ratio: team steps/s over single-robot steps/s; per robot-step: N x the CPU ratio (1 = no team overhead)"
    )


if __name__ == "__main__":
    main()
