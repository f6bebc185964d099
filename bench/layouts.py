"""Reset cost of every layout family at every tier: the layout alone, and a whole env reset.

Run with ``OPENBLAS_NUM_THREADS=1 python bench/layouts.py`` (``--smoke``: the hard tiers, a few seeds). Each
figure is the median over resets of different seeds (each seed is a new world, as in training, so no cache of
a wall set helps a generator whose walls are drawn). For scale, in the same run: an ``EKFSLAM-v0`` reset, and
the placement grid of the largest hard tier computed by ``free_cells`` against the brute-force distances it
replaces (every cell centre against every wall). Times are this thread's CPU time (``time.thread_time``), not
wall time, so other processes on a shared machine do not inflate them.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import gymnasium as gym
import numpy as np

import ekfslam_gym  # noqa: F401  (registers the ids)
from ekfslam_gym import compiled
from ekfslam_gym.sim import FAMILIES, TIERS, make_layout, world_section


def median_ms(call, seeds) -> float:
    times = []
    for seed in seeds:
        start = time.thread_time()
        call(seed)
        times.append(time.thread_time() - start)
    return 1e3 * statistics.median(times)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--resets", type=int, default=40, help="resets (seeds) per figure")
    parser.add_argument("--smoke", action="store_true", help="the hard tiers only, 3 resets each")
    args = parser.parse_args(argv)
    tiers = ("hard",) if args.smoke else TIERS
    seeds = range(100, 100 + (3 if args.smoke else args.resets))

    reference = gym.make("EKFSLAM-v0")
    reference.reset(seed=0)
    v0_ms = median_ms(lambda s: reference.reset(seed=s), seeds)
    print(f"kernels: {compiled.backend()}; EKFSLAM-v0 reset {v0_ms:.2f} ms (median of {len(seeds)})")
    print(
        f"{'family':<14}{'tier':<8}{'walls':>6}{'landmarks':>10}{'layout ms':>11}{'reset ms':>10}{'/ v0':>7}"
    )
    largest = (0.0, "", "")
    for family in FAMILIES:
        for tier in tiers:
            world = world_section(family, tier)
            kwargs, n = world["layout_kwargs"], world["n_landmarks"]
            layout_ms = median_ms(
                lambda s, f=family, n=n, k=kwargs: make_layout(f, np.random.default_rng(s), n, **k), seeds
            )
            env = gym.make("EKFSLAM-v0", world=world)
            env.reset(seed=0)
            reset_ms = median_ms(lambda s, e=env: e.reset(seed=s), seeds)
            walls = len(env.unwrapped.world.layout.walls)
            print(
                f"{family:<14}{tier:<8}{walls:>6}{n:>10}{layout_ms:>11.2f}{reset_ms:>10.2f}{reset_ms / v0_ms:>7.2f}"
            )
            area = kwargs["width"] * kwargs["height"]
            largest = max(largest, (area, family, tier))
            env.close()

    _, family, tier = largest
    world = world_section(family, tier)
    layout = make_layout(family, np.random.default_rng(0), world["n_landmarks"], **world["layout_kwargs"])
    cell, clearance = 0.197, 0.25 + 0.5 * 0.197  # the placement grid of the default clearances
    xmin, ymin, xmax, ymax = layout.bounds
    cols, rows = math.ceil((xmax - xmin) / cell), math.ceil((ymax - ymin) / cell)
    walls = np.ascontiguousarray(layout.walls)
    xs, ys = xmin + (np.arange(cols) + 0.5) * cell, ymin + (np.arange(rows) + 0.5) * cell
    centres = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    compiled.free_cells(walls, xmin, ymin, cell, rows, cols, clearance)
    fast = median_ms(lambda _: compiled.free_cells(walls, xmin, ymin, cell, rows, cols, clearance), seeds)
    brute = median_ms(lambda _: compiled.min_wall_distance(centres, walls) >= clearance, seeds)
    print(f"placement grid of {family} {tier} ({rows} x {cols} cells, {len(walls)} walls): free_cells "
          f"{fast:.3f} ms, brute force {brute:.3f} ms, ratio {brute / fast:.0f}x")  # fmt: skip


if __name__ == "__main__":
    main()
