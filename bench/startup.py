"""Benchmark: start-up of a new process (import, make, reset, one step) for EKFSLAM-v0 against CartPole-v1.

    OPENBLAS_NUM_THREADS=1 python bench/startup.py [--repeats 7] [--smoke]

Every subprocess vector-env worker and every command line pays this, so it is measured as a user meets it:
a fresh interpreter per sample, the two envs alternated so that a loaded machine slows both alike. Prints
the medians, their ratio, which kernel backend served the env (``aot`` when ``pip install`` compiled the
kernels, else numba's ``jit``) and whether numba or scipy were imported at all.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

PROGRAMS = {
    "EKFSLAM-v0": (
        "import gymnasium as gym, ekfslam_gym\n"
        "env = gym.make('EKFSLAM-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
    ),
    "CartPole-v1": (
        "import gymnasium as gym\nenv = gym.make('CartPole-v1'); env.reset(seed=0); env.step(env.action_space.sample())\n"
    ),
}
PROBE = (
    "import sys, json, gymnasium as gym, ekfslam_gym\n"
    "from ekfslam_gym import compiled\n"
    "env = gym.make('EKFSLAM-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
    "print(json.dumps({'backend': compiled.backend(), 'numba': 'numba' in sys.modules,"
    " 'scipy': 'scipy' in sys.modules, 'torch': 'torch' in sys.modules}))\n"
)


def wall_time(program: str, env: dict[str, str]) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", program], check=True, env=env)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--smoke", action="store_true", help="one repeat (a check that the script runs)")
    args = parser.parse_args()
    repeats = 1 if args.smoke else args.repeats
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    probe = json.loads(
        subprocess.run(
            [sys.executable, "-c", PROBE], env=env, check=True, capture_output=True, text=True
        ).stdout
    )
    samples: dict[str, list[float]] = {name: [] for name in PROGRAMS}
    for _ in range(repeats):
        for name, program in PROGRAMS.items():
            samples[name].append(wall_time(program, env))
    medians = {name: statistics.median(values) for name, values in samples.items()}
    print(
        f"kernels: {probe['backend']}; imported numba: {probe['numba']}, scipy: {probe['scipy']}, torch: {probe['torch']}"
    )
    for name, value in medians.items():
        print(f"{name:12s} new process import + make + reset + step: {value:.3f} s (median of {repeats})")
    print(f"ratio EKFSLAM-v0 / CartPole-v1: {medians['EKFSLAM-v0'] / medians['CartPole-v1']:.2f}")


if __name__ == "__main__":
    main()
