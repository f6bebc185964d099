"""Benchmark: start-up of a new process, as every command line and subprocess worker pays it.

    OPENBLAS_NUM_THREADS=1 python bench/startup.py [--repeats 5] [--smoke]

Three figures, each from fresh interpreters, the programs alternated within every repeat so that a loaded machine
slows them alike, medians of the repeats:

1. import, make, reset and one step of EKFSLAM-v0 against CartPole-v1;
2. every installed ``ekfslam-<command> --help`` against a process that imports ``ekfslam_gym`` and makes
   EKFSLAM-v0: a command's help should import only its parser (within 2x of that process);
3. the replay of a 200-landmark recording end to end (``ekfslam-replay --data ... --world ... --json``, process
   included) against the same recording through the course's full-matrix EKF-SLAM (dense G, F_x,j and H,
   (I - K H) Sigma, as the course's lecture notes write it; numpy alone, in its own process). The two final poses
   are printed beside the ratio: both forms compute the same filter.

Also prints which kernel backend served the env (``aot`` when ``pip install`` compiled the kernels, else numba's
``jit``) and whether numba, scipy or torch were imported.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from importlib import metadata
from pathlib import Path

BIN = Path(sys.executable).parent
PROGRAMS = {
    "EKFSLAM-v0": (
        "import gymnasium as gym, ekfslam_gym\n"
        "env = gym.make('EKFSLAM-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
    ),
    "CartPole-v1": (
        "import gymnasium as gym\nenv = gym.make('CartPole-v1'); env.reset(seed=0); env.step(env.action_space.sample())\n"
    ),
}
MAKE = "import gymnasium as gym, ekfslam_gym\ngym.make('EKFSLAM-v0')\n"
PROBE = (
    "import sys, json, gymnasium as gym, ekfslam_gym\n"
    "from ekfslam_gym import compiled\n"
    "env = gym.make('EKFSLAM-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
    "print(json.dumps({'backend': compiled.backend(), 'numba': 'numba' in sys.modules,"
    " 'scipy': 'scipy' in sys.modules, 'torch': 'torch' in sys.modules}))\n"
)
# A loop of ~110 m, one lap at 0.2 m a step (524 steps), 200 landmarks within 2.25 m of it: ~8 readings a step.
RECORDING = dict(n_landmarks=200, field_size=40.0, min_separation=0.5, width=30.0, height=25.0, corner_radius=3.0,
                 max_range=2.5, laps=1, step_length=0.2)  # fmt: skip
SMOKE_RECORDING = dict(
    n_landmarks=20, laps=1
)  # --smoke: the course-sized drive, a check that the script runs
# The course's EKF-SLAM as its lecture notes write it (bench/ekf.py times its single steps): full n x n products.
FULL_MATRIX = """
import json, math, sys
import numpy as np
from ekfslam_gym.angles import wrap_angle
from ekfslam_gym.data.course import read_sensor_data, read_world
from ekfslam_gym.filter.models import odometry_motion, range_bearing

data, world = read_sensor_data(sys.argv[1]), read_world(sys.argv[2])
slot = {int(i): k for k, i in enumerate(np.sort(world.ids))}
n = 3 + 2 * len(slot)
R, Q = np.diag([0.1, 0.1, 0.01]), 0.01 * np.eye(2)
mean, cov = np.zeros(n), np.zeros((n, n))
cov[3:, 3:] = 1000.0 * np.eye(n - 3)
observed = np.zeros(len(slot), dtype=bool)
Fx = np.zeros((3, n))
Fx[:, :3] = np.eye(3)
for step in data:
    pose, g, _ = odometry_motion(mean[:3], *step.odometry)
    G = np.eye(n) + Fx.T @ (g - np.eye(3)) @ Fx
    mean[:3] = pose
    cov = G @ cov @ G.T + Fx.T @ R @ Fx
    if not len(step.ids):
        continue
    rows, innovations = [], []
    for i, (r, phi) in zip(step.ids, step.z):
        j = slot[int(i)]
        if not observed[j]:
            mean[3 + 2 * j : 5 + 2 * j] = mean[:2] + r * np.array([math.cos(mean[2] + phi), math.sin(mean[2] + phi)])
            observed[j] = True
        Fxj = np.zeros((5, n))
        Fxj[:3, :3] = np.eye(3)
        Fxj[3:, 3 + 2 * j : 5 + 2 * j] = np.eye(2)
        zhat, Hx, Hm = range_bearing(mean[:3], mean[3 + 2 * j : 5 + 2 * j], 1e-3)
        rows.append(np.hstack([Hx, Hm]) @ Fxj)
        innovations.append([r - zhat[0], wrap_angle(phi - zhat[1])])
    H = np.vstack(rows)
    S = H @ cov @ H.T + np.kron(np.eye(len(rows)), Q)
    K = cov @ H.T @ np.linalg.inv(S)
    mean = mean + K @ np.concatenate(innovations)
    mean[2] = wrap_angle(mean[2])
    cov = (np.eye(n) - K @ H) @ cov
print(json.dumps({"pose": mean[:3].tolist()}))
"""


def wall_time(command: list[str], env: dict[str, str]) -> tuple[float, str]:
    start = time.perf_counter()
    done = subprocess.run(command, check=True, env=env, capture_output=True, text=True)
    return time.perf_counter() - start, done.stdout


def commands() -> list[str]:
    """The installed ``ekfslam-*`` console scripts of this package."""
    scripts = metadata.entry_points(group="console_scripts")
    return sorted(s.name for s in scripts if s.name.startswith("ekfslam-") and (BIN / s.name).is_file())


def write_recording(folder: Path, recording: dict) -> tuple[Path, Path]:
    from ekfslam_gym.data.synthetic import simulate_drive

    return simulate_drive(0, **recording).write(folder)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--smoke", action="store_true", help="one repeat (a check that the script runs)")
    args = parser.parse_args()
    repeats = 1 if args.smoke else args.repeats
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    python = [sys.executable, "-c"]
    probe = json.loads(wall_time([*python, PROBE], env)[1])
    helps = {name: [str(BIN / name), "--help"] for name in commands()}
    with tempfile.TemporaryDirectory() as tmp:
        recording = SMOKE_RECORDING if args.smoke else RECORDING
        data, world = write_recording(Path(tmp), recording)
        programs = {
            **{name: [*python, program] for name, program in PROGRAMS.items()},
            "make": [*python, MAKE],
            **helps,
            "replay": [str(BIN / "ekfslam-replay"), "--data", str(data), "--world", str(world), "--json"],
            "full-matrix": [*python, FULL_MATRIX, str(data), str(world)],
        }
        samples: dict[str, list[float]] = {name: [] for name in programs}
        poses: dict[str, list[float]] = {}
        for _ in range(repeats):
            for name, command in programs.items():
                seconds, out = wall_time(command, env)
                samples[name].append(seconds)
                if name in ("replay", "full-matrix"):
                    poses[name] = json.loads(out)["pose"]
    medians = {name: statistics.median(values) for name, values in samples.items()}
    print(
        f"kernels: {probe['backend']}; imported numba: {probe['numba']}, scipy: {probe['scipy']}, torch: {probe['torch']}"
    )
    for name in PROGRAMS:
        print(
            f"{name:12s} new process import + make + reset + step: {medians[name]:.3f} s (median of {repeats})"
        )
    print(f"ratio EKFSLAM-v0 / CartPole-v1: {medians['EKFSLAM-v0'] / medians['CartPole-v1']:.2f}")
    base = medians["make"]
    print(f"\nimport ekfslam_gym + make EKFSLAM-v0: {base:.3f} s; each command's --help against it:")
    for name in helps:
        print(f"  {name + ' --help':28s} {medians[name]:.3f} s  {medians[name] / base:.2f}x")
    worst = max(helps, key=medians.get)
    print(f"slowest --help: {worst}, {medians[worst] / base:.2f}x the import + make")
    print(
        f"\n{recording['n_landmarks']}-landmark replay end to end (process included): "
        f"ekfslam-replay {medians['replay']:.3f} s, full-matrix form {medians['full-matrix']:.3f} s; "
        f"{medians['full-matrix'] / medians['replay']:.1f}x faster"
    )
    gap = max(abs(a - b) for a, b in zip(poses["replay"], poses["full-matrix"]))
    print(
        f"final poses: ekfslam-replay {poses['replay']}, full-matrix {poses['full-matrix']} (max difference {gap:.1e})"
    )


if __name__ == "__main__":
    main()
