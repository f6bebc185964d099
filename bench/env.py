"""Benchmark: raw env steps/s of EKFSLAM-v0, with a breakdown, and of every registered id (the family ids at
every tier), each against CartPole-v1 in the same run, with the milliseconds a reset takes.

    OPENBLAS_NUM_THREADS=1 python bench/env.py [--steps 20000] [--landmarks 10 50 200]

Raw means one process, random actions drawn beforehand, no agent. The breakdown times each stage of a step
on its own over the same kind of drive, as the env runs it at the default config: physics (pymunk), readings
(wheel odometry and landmark readings, one call), filter (``EKFSLAM.update``: predict and correct),
observation (its kernel, with the wall scan, and the copy handed out) and the rest of ``step`` (coverage
memory, reward, metrics, info: the env's own glue).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402

import ekfslam_gym  # noqa: E402, F401
from ekfslam_gym import compiled  # noqa: E402
from ekfslam_gym.envs import EKFSLAMEnv  # noqa: E402
from ekfslam_gym.envs.observation import observation_constants  # noqa: E402


def steps_per_second(env, actions: np.ndarray, seed: int = 0, clock=time.perf_counter) -> float:
    """Steps per second of ``clock``: wall time by default, or ``time.process_time`` (this process's CPU time,
    which other jobs on a shared machine change far less than the wall time)."""
    env.reset(seed=seed)
    step = env.step
    start = clock()
    for action in actions:
        _, _, terminated, truncated, _ = step(action)
        if terminated or truncated:
            env.reset()
    return len(actions) / (clock() - start)


def breakdown(overrides: dict, steps: int) -> dict[str, float]:
    """Microseconds per step of each stage, replaying one recorded drive stage by stage."""
    env = EKFSLAMEnv(**overrides, max_episode_steps=10**9, done_std=0.0)
    env.reset(seed=0)
    world, ekf, rng = env.world, env.filter, env.np_random
    actions = np.random.default_rng(1).uniform(-1, 1, (steps, 2))
    cfg = env.config
    v_max, w_max = cfg.robot.v_max, cfg.robot.omega_max
    layout, constants = env.observation_layout, observation_constants(cfg.observation, cfg.sensor)
    out = np.zeros(layout.size, dtype=np.float32)
    memory, bounds = env.coverage_memory, env.bounds
    # Read-only views of the filter's state, fetched once as the env does (the filter updates them in place).
    mean, cov, observed, pose_given_map = ekf.mean, ekf.cov, ekf.observed, ekf.pose_cov_given_map
    timings = dict.fromkeys(["physics", "readings", "filter", "observation", "total step"], 0.0)
    clock = time.perf_counter
    for a in actions:
        t0 = clock()
        world.step(a[0] * v_max, a[1] * w_max)
        t1 = clock()
        odometry, readings = world.wheel_odometry_and_readings(rng)
        t3 = clock()
        ekf.update(odometry.u, odometry.cov, readings.ids, readings.z)
        t4 = clock()
        compiled.fill_observation(
            out, layout.offsets, constants, mean, cov, observed, ekf.log_det, pose_given_map, world.scan(), memory,
            bounds, 0.5,
        )  # fmt: skip
        out.copy()
        t5 = clock()
        timings["physics"] += t1 - t0
        timings["readings"] += t3 - t1
        timings["filter"] += t4 - t3
        timings["observation"] += t5 - t4
    env.reset(seed=0)
    timings["total step"] = 1.0 / steps_per_second(env, actions.astype(np.float32))
    for key in timings:
        if key != "total step":
            timings[key] /= steps
    timings["rest of step"] = timings["total step"] - sum(v for k, v in timings.items() if k != "total step")
    return {k: v * 1e6 for k, v in timings.items()}


def registered_ids() -> list[tuple[str, str | None]]:
    """(id, tier) of every registered EKFSLAM id; the family ids at each tier (the hard tier is the largest)."""
    from ekfslam_gym.envs.presets import FAMILY_IDS, TIERS

    found: list[tuple[str, str | None]] = []
    for env_id in sorted(i for i in gym.registry if i.startswith("EKFSLAM")):
        found += [(env_id, t) for t in TIERS] if env_id in FAMILY_IDS else [(env_id, None)]
    return found


def id_ratio(
    env_id: str, tier: str | None, actions, cart_actions, cartpole, rounds: int = 3
) -> tuple[float, float]:
    """(best ratio of the id's raw steps/s to CartPole-v1's, the id's best rate), the two measured alternately
    ``rounds`` times so that a passing load slows both alike."""
    kwargs = {} if tier is None else {"tier": tier}
    EKFSLAMEnv(preset=env_id, **kwargs).reset(seed=0)  # warm up outside the timing
    ratio = rate = 0.0
    for _ in range(rounds):
        cart = steps_per_second(cartpole, cart_actions)
        mine = steps_per_second(EKFSLAMEnv(preset=env_id, **kwargs), actions)
        ratio, rate = max(ratio, mine / cart), max(rate, mine)
    return ratio, rate


def reset_ms(env_id: str, tier: str | None, resets: int = 20) -> float:
    """Milliseconds of this process's CPU time per ``reset`` (a new world, layout and filter), best of three
    runs of ``resets`` seeds (CPU time: a busy machine changes it far less than the wall time)."""
    env = EKFSLAMEnv(preset=env_id, **({} if tier is None else {"tier": tier}))
    env.reset(seed=0)
    best = math.inf
    for _ in range(3):
        start = time.process_time()
        for seed in range(resets):
            env.reset(seed=seed)
        best = min(best, (time.process_time() - start) / resets)
    return best * 1e3


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--landmarks", type=int, nargs="+", default=[10, 50, 200])
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: a check that the script runs")
    args = parser.parse_args(argv)
    if args.smoke:
        args.steps, args.landmarks = 300, [10]
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (args.steps, 2)).astype(np.float32)

    cartpole = gym.make("CartPole-v1").unwrapped
    cart_actions = rng.integers(0, 2, args.steps)
    EKFSLAMEnv().reset(seed=0)  # load the kernels outside the timing
    # The ratio's two rates, best of five, measured alternately so that a passing load slows both alike.
    cart_rate = ekf_rate = cart_cpu = ekf_cpu = 0.0
    for _ in range(5):
        cart_rate = max(cart_rate, steps_per_second(cartpole, cart_actions))
        ekf_rate = max(ekf_rate, steps_per_second(EKFSLAMEnv(), actions))
        cart_cpu = max(cart_cpu, steps_per_second(cartpole, cart_actions, clock=time.process_time))
        ekf_cpu = max(ekf_cpu, steps_per_second(EKFSLAMEnv(), actions, clock=time.process_time))

    configs = [("default (30)", {})] + [(str(n), {"world": {"n_landmarks": n}}) for n in args.landmarks]
    print(f"OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}, {args.steps} random-action steps each")
    print(
        f"CartPole-v1 unwrapped: {cart_rate:,.0f} steps/s; EKFSLAM-v0 unwrapped, default config: {ekf_rate:,.0f}"
    )
    print(f"ratio EKFSLAM-v0 / CartPole-v1 (alternated, best of five each): {ekf_rate / cart_rate:.3f}")
    print(
        f"the same by this process's CPU time (less sensitive to other jobs): {ekf_cpu / cart_cpu:.3f} "
        f"({ekf_cpu:,.0f} vs {cart_cpu:,.0f} steps per CPU second)"
    )
    print(f"{'landmarks':>12} | {'unwrapped':>10} {'gym.make':>10} | {'vs CartPole':>11} {'ratio':>6}")
    for name, overrides in configs:
        EKFSLAMEnv(**overrides).reset(seed=0)  # compile and warm up outside the timing
        raw = made = 0.0
        for _ in range(3):  # best of three, interleaved, so neither order nor a passing load decides
            raw = max(raw, steps_per_second(EKFSLAMEnv(**overrides), actions))
            made = max(made, steps_per_second(gym.make("EKFSLAM-v0", **overrides), actions))
        print(
            f"{name:>12} | {raw:>10,.0f} {made:>10,.0f} | 1/{cart_rate / raw:>9.1f} {raw / cart_rate:>6.3f}"
        )
    print("\nevery registered id, unwrapped, its own config (velocity actions), alternated with CartPole-v1:")
    print(f"{'id':>28} | {'steps/s':>9} {'ratio':>6} | {'reset, CPU ms':>13}")
    steps = min(args.steps, 5_000)
    for env_id, tier in registered_ids():
        rounds = 1 if args.smoke else 3
        ratio, rate = id_ratio(env_id, tier, actions[:steps], cart_actions[:steps], cartpole, rounds)
        label = env_id if tier is None else f"{env_id}:{tier}"
        print(f"{label:>28} | {rate:>9,.0f} {ratio:>6.3f} | {reset_ms(env_id, tier, 3 * rounds):>13.2f}")
    print("\nbreakdown at the default config, microseconds per step:")
    for stage, us in breakdown({}, min(args.steps, 10_000)).items():
        print(f"  {stage:>12}: {us:6.1f}")


if __name__ == "__main__":
    main()
