"""Micro-benchmark of the simulator's step: physics, odometry, sensing and the wall scan, per call.

Run with ``OPENBLAS_NUM_THREADS=1 python bench/sim.py``. A scripted driver (forward, turning away when the scan
sees a wall ahead) drives the robot as a policy would, so the costs are those of a real episode; each part is
timed with ``perf_counter`` around its call. A collision rebuilds the world (not timed, counted). For
comparison it times the same occlusion and scan queries through pymunk's ``segment_query_first``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
import pymunk

from ekfslam_gym.sim import World, make_layout
from ekfslam_gym.sim.robot import WALL_CATEGORY


def drive(
    layout_name: str, n_landmarks: int, n_steps: int, size: float = 20.0, seed: int = 0
) -> dict[str, float]:
    """Mean microseconds per call of each part over n_steps steps of the scripted driver."""
    rng = np.random.default_rng(seed)
    world = World(make_layout(layout_name, rng, n_landmarks, width=size, height=size))
    totals = dict.fromkeys(("physics", "odometry", "velocity", "sense", "scan"), 0.0)
    readings = 0
    rebuilds = 0
    scan = world.scan()
    clock = time.perf_counter
    for k in range(n_steps):
        ahead = min(scan[0], scan[1], scan[-1])
        v, omega = (0.8, 0.6 * math.sin(0.05 * k)) if ahead > 1.0 else (0.1, 1.5)
        t0 = clock()
        collided = world.step(v, omega)
        t1 = clock()
        world.odometry(rng)
        t2 = clock()
        world.velocity_odometry(rng)
        t3 = clock()
        readings += len(world.sense(rng).ids)
        t4 = clock()
        scan = world.scan()
        t5 = clock()
        for key, dt in zip(totals, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4)):
            totals[key] += dt
        if collided:
            rebuilds += 1
            world = World(make_layout(layout_name, rng, n_landmarks, width=size, height=size))
            scan = world.scan()
    out = {key: 1e6 * value / n_steps for key, value in totals.items()}
    out["readings"] = readings / n_steps
    out["rebuilds"] = rebuilds
    out["walls"] = len(world.layout.walls)
    return out


def pymunk_queries(layout_name: str, n_landmarks: int, n_calls: int) -> tuple[float, float, int]:
    """Microseconds for the occlusion of the landmarks in range and a 16-beam scan via segment_query_first."""
    world = World(make_layout(layout_name, np.random.default_rng(0), n_landmarks))
    space = world.space
    wall_filter = pymunk.ShapeFilter(mask=WALL_CATEGORY)
    x, y, theta = world.pose
    landmarks = world.layout.landmarks
    near = [tuple(p) for p in landmarks if math.hypot(p[0] - x, p[1] - y) <= world.sensor_params.max_range]
    r = world.sensor_params.scan_max_range
    ends = [(x + r * math.cos(theta + a), y + r * math.sin(theta + a)) for a in world.sensor.beam_angles]
    t0 = time.perf_counter()
    for _ in range(n_calls):
        for p in near:
            space.segment_query_first((x, y), p, 0.0, wall_filter)
    t1 = time.perf_counter()
    for _ in range(n_calls):
        for p in ends:
            space.segment_query_first((x, y), p, 0.0, wall_filter)
    t2 = time.perf_counter()
    return 1e6 * (t1 - t0) / n_calls, 1e6 * (t2 - t1) / n_calls, len(near)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--landmarks", type=int, default=30)
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--size", type=float, default=20.0, help="world width and height, m")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes: a check that the script runs")
    args = parser.parse_args(argv)
    queries = 2000
    if args.smoke:
        args.steps, queries = 200, 50
    drive("arena", args.landmarks, 200)  # compile / load the numba cache outside the timing
    print(
        f"{args.landmarks} landmarks, {args.size:g} x {args.size:g} m, {args.steps} steps per layout, µs per call"
    )
    header = f"{'layout':8s}{'walls':>6s}{'physics':>9s}{'odom':>7s}{'vel':>7s}{'sense':>7s}{'scan':>7s}"
    print(header + f"{'step*':>8s}{'reads':>7s}{'rebuilds':>9s}")
    for name in ("arena", "rooms", "loop"):
        t = drive(name, args.landmarks, args.steps, args.size)
        step = t["physics"] + t["odometry"] + t["sense"] + t["scan"]
        print(
            f"{name:8s}{t['walls']:6d}{t['physics']:9.2f}{t['odometry']:7.2f}{t['velocity']:7.2f}"
            f"{t['sense']:7.2f}{t['scan']:7.2f}{step:8.2f}{t['readings']:7.1f}{t['rebuilds']:9d}"
        )
    print("* step = physics + odometry + sense + scan (one motion model)")
    for name in ("arena", "rooms"):
        occ, scan, n_near = pymunk_queries(name, args.landmarks, queries)
        print(
            f"pymunk segment_query_first ({name}): {n_near} occlusion queries {occ:.2f} us, 16 beams {scan:.2f} us"
        )


if __name__ == "__main__":
    main()
