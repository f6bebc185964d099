"""Benchmark: end-to-end PPO env steps/s (collection and updates) with Dummy and Subproc vector envs.

    OPENBLAS_NUM_THREADS=1 python bench/train.py [--steps 16384] [--n-envs 1 2 8]

Uses the hyperparameters of configs/ppo.yaml for EKFSLAM-v0 (n_steps scaled so every setting collects
rollouts of the same size), torch on one thread, no evaluation or checkpoints: what train.py spends per step.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import yaml  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def measure(vec: str, n_envs: int, steps: int, hyper: dict) -> float:
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecNormalize

    torch.set_num_threads(1)
    cls = SubprocVecEnv if vec == "subproc" else DummyVecEnv
    env = VecNormalize(make_vec_env("ekfslam_gym:EKFSLAM-v0", n_envs=n_envs, seed=0, vec_env_cls=cls))
    model = PPO("MlpPolicy", env, seed=0, verbose=0, **hyper)
    model.learn(total_timesteps=hyper["n_steps"] * n_envs)  # warm up: compile, spawn, first update
    start = time.perf_counter()
    model.learn(total_timesteps=steps, reset_num_timesteps=False)
    rate = steps / (time.perf_counter() - start)
    env.close()
    return rate


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--steps", type=int, default=16_384)
    parser.add_argument("--n-envs", type=int, nargs="+", default=[1, 2, 8])
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: a check that the script runs")
    args = parser.parse_args(argv)
    from ekfslam_gym.training.settings import schedule  # rl-zoo3's "lin_X" schedules, as train.py reads them

    entry = yaml.safe_load((ROOT / "configs" / "ppo.yaml").read_text())["EKFSLAM-v0"]
    keys = ("n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda", "learning_rate", "ent_coef", "clip_range",
            "policy_kwargs")  # fmt: skip
    base = {
        k: schedule(entry[k]) if k in ("learning_rate", "clip_range") else entry[k]
        for k in keys
        if k in entry
    }
    if args.smoke:
        args.steps, args.n_envs = 128, [2]
        base.update(n_epochs=1, batch_size=64)
        entry = {**entry, "n_envs": 2, "n_steps": 32}
        base["n_steps"] = 32
    rollout = base["n_steps"] * entry["n_envs"]
    print(f"PPO on EKFSLAM-v0, {args.steps} steps per setting, rollouts of {rollout} steps, torch 1 thread")
    for n_envs in args.n_envs:
        for vec in ("dummy", "subproc"):
            if vec == "subproc" and n_envs == 1:
                continue
            hyper = {**base, "n_steps": max(32, rollout // n_envs)}
            rate = measure(vec, n_envs, args.steps, hyper)
            print(f"  {vec:>8} x {n_envs}: {rate:7,.0f} env steps/s")


if __name__ == "__main__":
    main()
