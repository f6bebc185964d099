"""Benchmark: control steps/s of each action interface, against the plain velocity action in the same run.

    OPENBLAS_NUM_THREADS=1 python bench/actions.py [--env-id EKFSLAM-Large-v0] [--decisions 2000] [--repeats 3]
        [--smoke]

Each interface drives ``--decisions`` random actions (drawn beforehand, seeded) from one seeded reset, resetting
when an episode ends; one macro action of ``primitives`` or ``waypoint`` is ``hold`` (10) control steps or
fewer (``info["inner_steps"]``), so the figure is control steps/s: what the macro interface adds to a step of
the simulator and filter (the waypoint controller's scan geometry, the primitives' guard). The interfaces take
turns, ``--repeats`` times, and each reports its best round (the least disturbed by the rest of the machine).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import gymnasium as gym  # noqa: E402

import ekfslam_gym  # noqa: E402, F401
from ekfslam_gym import compiled  # noqa: E402

INTERFACES = {
    "velocity": {"kind": "velocity"},
    "primitives": {"kind": "primitives", "hold": 10},
    "primitives, guard 0.1": {"kind": "primitives", "hold": 10, "guard": 0.1},
    "waypoint": {"kind": "waypoint", "hold": 10},
}


def control_steps_per_second(env_id: str, action: dict, decisions: int, seed: int = 0) -> float:
    """Control steps/s over ``decisions`` seeded random actions of the ``action`` interface."""
    env = gym.make(env_id, action=action)
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(decisions)]
    env.reset(seed=seed)
    steps = 0
    start = time.perf_counter()
    for a in actions:
        _, _, terminated, truncated, info = env.step(a)
        steps += info.get("inner_steps", 1)
        if terminated or truncated:
            env.reset()
    elapsed = time.perf_counter() - start
    env.close()
    return steps / elapsed


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env-id", default="EKFSLAM-Large-v0")
    parser.add_argument("--decisions", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: a check that the script runs")
    args = parser.parse_args(argv)
    if args.smoke:
        args.decisions, args.repeats = 20, 1
    for action in INTERFACES.values():  # warm up: numba's JIT when the ahead-of-time kernels are absent
        control_steps_per_second(args.env_id, action, 5)
    best = dict.fromkeys(INTERFACES, 0.0)
    for _ in range(args.repeats):
        for name, action in INTERFACES.items():
            best[name] = max(best[name], control_steps_per_second(args.env_id, action, args.decisions))
    print(f"{args.env_id}: {args.decisions} random actions per interface, best of {args.repeats} rounds "
          f"(kernels: {compiled.backend()})")  # fmt: skip
    print(f"{'interface':<22} {'control steps/s':>16} {'/ velocity':>11}")
    for name, rate in best.items():
        print(f"{name:<22} {rate:16.0f} {rate / best['velocity']:11.2f}")


if __name__ == "__main__":
    main()
