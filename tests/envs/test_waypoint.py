"""The waypoint controller: its clearance geometry against brute force, its control law, and real drives."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from ekfslam_gym.agents.base import wall_scan

import ekfslam_gym  # noqa: F401  (registers the env ids)
from ekfslam_gym.envs.waypoint import Command, WaypointController, goal_in_world, travel_distance

SCAN_MAX = 5.0


def _controller(**kwargs) -> WaypointController:
    return WaypointController(1.0, 2.0, 0.2, 16, SCAN_MAX, 0.1, **kwargs)


def _walls(xs, ys, hit, join):
    points = [(x, y) for x, y, h in zip(xs, ys, hit) if h]
    n = len(xs)
    segments = [
        (xs[i], ys[i], xs[(i + 1) % n], ys[(i + 1) % n])
        for i in range(n)
        if hit[i] and hit[(i + 1) % n] and math.hypot(xs[i] - xs[(i + 1) % n], ys[i] - ys[(i + 1) % n]) < join
    ]
    return points, segments


def _distance_to_walls(px, points, segments):
    """Distance from (px, 0) to the nearest wall point or segment."""
    d = min((math.hypot(x - px, y) for x, y in points), default=math.inf)
    for ax, ay, bx, by in segments:
        dx, dy = bx - ax, by - ay
        t = min(max(((px - ax) * dx - ay * dy) / (dx * dx + dy * dy), 0.0), 1.0)
        d = min(d, math.hypot(ax + t * dx - px, ay + t * dy))
    return d


def test_travel_distance_matches_a_brute_force_sweep_of_the_disc():
    rng = np.random.default_rng(0)
    rho, join, step = 0.25, 1.5, 1e-3
    sweep = np.arange(0.0, 6.0, step)
    checked = 0
    for _ in range(150):
        ranges = rng.uniform(0.2, SCAN_MAX, 16)
        ranges[rng.random(16) < 0.3] = SCAN_MAX
        angles = 2.0 * np.pi * np.arange(16) / 16 + rng.uniform(-0.5, 0.5)
        xs, ys = list(ranges * np.cos(angles)), list(ranges * np.sin(angles))
        hit = list(ranges < SCAN_MAX)
        points, segments = _walls(xs, ys, hit, join)
        if _distance_to_walls(0.0, points, segments) <= rho:
            continue  # starting in contact: covered by the next test
        inside = [s for s in sweep if _distance_to_walls(s, points, segments) < rho]
        expected = inside[0] if inside else math.inf
        got = travel_distance(xs, ys, hit, rho, join)
        if math.isinf(expected):
            assert math.isinf(got)
        else:
            assert got == pytest.approx(expected, abs=2 * step)
        checked += 1
    assert checked > 100


def test_travel_distance_in_contact_blocks_only_walls_in_front():
    rho = 0.25
    # a wall across the way, already overlapping the disc in front: no room at all
    assert travel_distance([0.2, 0.2], [-0.3, 0.3], [True, True], rho, 1.5) == 0.0
    # the same wall behind the centre: moving on takes the robot away from it
    assert math.isinf(travel_distance([-0.2, -0.2], [-0.3, 0.3], [True, True], rho, 1.5))
    # a wall alongside, parallel to the way, just outside the disc: nothing in the way
    assert math.isinf(travel_distance([-1.0, 1.0], [0.3, 0.3], [True, True], rho, 2.5))
    # a point straight ahead: contact after its distance less the radius
    assert travel_distance([2.0], [0.0], [True], rho, 1.5) == pytest.approx(1.75)
    # end points too far apart are not joined: the disc passes between them
    assert math.isinf(travel_distance([2.0, 2.0], [-1.0, 1.0], [True, True], rho, 1.5))
    assert travel_distance([2.0, 2.0], [-1.0, 1.0], [True, True], rho, 2.5) == pytest.approx(1.75)
    with pytest.raises(ValueError, match="one entry per beam"):
        travel_distance([2.0, 2.0], [0.0], [True, True], rho, 1.5)


def test_the_compiled_clearances_equal_travel_distance_over_the_scans_end_points():
    """``clearances`` (one compiled call over the scan) against ``travel_distance`` on the end points it implies,
    ahead and mirrored behind, including beams that saw nothing and scans in contact."""
    c = _controller()
    angles = 2.0 * np.pi * np.arange(16) / 16
    rng = np.random.default_rng(2)
    for _ in range(300):
        ranges = rng.uniform(0.1, SCAN_MAX, 16)
        ranges[rng.random(16) < 0.3] = SCAN_MAX
        xs, ys, hit = ranges * np.cos(angles), ranges * np.sin(angles), ranges < SCAN_MAX - 1e-6
        expected = (
            travel_distance(xs, ys, hit, c._rho, c.join),
            travel_distance(-xs, ys, hit, c._rho, c.join),
        )
        assert c.clearances(ranges) == pytest.approx(expected, abs=1e-12)
        assert c.clearance_ahead(ranges) == pytest.approx(expected[0], abs=1e-12)


def test_control_law_in_free_space():
    c = _controller()
    free = np.full(16, SCAN_MAX)
    ahead = c.command((1.0, 1.0, 0.0), (5.0, 1.0), free)
    assert ahead == Command(1.0, 0.0, False, False)
    left = c.command((1.0, 1.0, 0.0), (1.0, 5.0), free)
    assert left.v == 0.0 and left.omega == 1.0 and not left.reached  # 90 degrees off: turn in place
    behind = c.command((1.0, 1.0, 0.0), (-3.0, 1.2), free)
    assert behind.v == 0.0 and behind.omega > 0.0
    slight = c.command((0.0, 0.0, 0.0), (4.0, -0.4), free)
    assert 0.0 < slight.v < 1.0 and slight.omega == pytest.approx(3.0 * math.atan2(-0.4, 4.0) / 2.0)
    near = c.command((0.0, 0.0, 0.0), (0.45, 0.0), free)
    assert near.v == pytest.approx(0.45 / 0.6)  # slowing within slow_distance
    assert c.command((0.0, 0.0, 0.0), (0.2, 0.1), free) == Command(0.0, 0.0, True, False)
    assert np.array_equal(ahead.action(), np.array([1.0, 0.0], dtype=np.float32))


def test_a_wall_ahead_caps_the_speed_then_blocks():
    c = _controller()
    goal = (10.0, 0.0)
    scan = np.full(16, SCAN_MAX)
    for distance, expected in ((1.0, 1.0), (0.6, (0.6 - 0.25 - 0.15) / 0.3), (0.45, (0.45 - 0.4) / 0.3)):
        scan[0] = distance
        command = c.command((0.0, 0.0, 0.0), goal, scan)
        assert command.v == pytest.approx(expected) and not command.blocked
    scan[0] = 0.4
    blocked = c.command((0.0, 0.0, 0.0), goal, scan)
    assert blocked.blocked and blocked.v == 0.0 and abs(blocked.omega) == 1.0
    scan[0] = 0.22  # closer than the inflated radius: back off, the way behind is free
    assert c.command((0.0, 0.0, 0.0), goal, scan).v < 0.0
    scan[8] = 0.3  # and boxed in behind too: stay put, only turn
    assert c.command((0.0, 0.0, 0.0), goal, scan).v == 0.0
    # the same wall does not stop a turn towards a goal to the side
    assert c.command((0.0, 0.0, 0.0), (0.0, -5.0), scan).omega == -1.0


def test_actions_are_finite_valid_and_deterministic():
    c = _controller()
    rng = np.random.default_rng(1)
    for _ in range(500):
        pose = (*rng.uniform(-10, 10, 2), rng.uniform(-10, 10))
        goal = rng.uniform(-10, 10, 2)
        scan = np.minimum(rng.uniform(0.05, 8.0, 16), SCAN_MAX)
        first = c.command(pose, goal, scan)
        assert first == c.command(np.array(pose), goal.copy(), scan.copy())
        action = first.action()
        assert action.shape == (2,) and np.all(np.isfinite(action)) and np.all(np.abs(action) <= 1.0)
    with pytest.raises(ValueError, match="beams"):
        c.command((0.0, 0.0, 0.0), (5.0, 0.0), np.full(8, SCAN_MAX))
    with pytest.raises(ValueError, match="finite"):
        c.command((0.0, math.nan, 0.0), (5.0, 0.0), np.full(16, SCAN_MAX))


def test_goal_in_world_turns_a_relative_goal_with_the_pose():
    x, y = goal_in_world((1.0, 2.0, 0.5 * math.pi), 3.0, 1.0)
    assert (x, y) == pytest.approx((0.0, 5.0))


def _run(env_id, seed, goal_of, steps):
    env = gym.make(env_id)
    observation, info = env.reset(seed=seed)
    u = env.unwrapped
    controller = WaypointController.from_config(u.config)
    goal = goal_of(u)
    true_xy, collisions, reached = [], 0, False
    for _ in range(steps):
        command = controller.command(u.filter.pose, goal, wall_scan(u, observation))
        if command.reached:
            reached = True
            break
        observation, _, _, _, info = env.step(command.action())
        true_xy.append(info["true_pose"][:2])
        collisions += info["collision"]
    env.close()
    return np.array(goal), np.array(true_xy), collisions, reached, controller


@pytest.mark.parametrize("seed", [0, 3])
def test_drives_to_a_free_goal_in_the_arena(seed):
    def goal_of(u):  # 4 m away, 60 degrees to the left of the start heading, well inside the walls
        start = u.world.layout.start
        for turn in np.linspace(1.0, 7.0, 13):
            goal = start[:2] + 4.0 * np.array([math.cos(start[2] + turn), math.sin(start[2] + turn)])
            if np.all(goal > 1.5) and np.all(goal < 18.5):
                return goal
        raise AssertionError("no free goal")

    goal, true_xy, collisions, reached, controller = _run("EKFSLAM-v0", seed, goal_of, 120)
    assert reached and len(true_xy) < 80  # 4 m at 1 m/s plus a turn: about 50 steps
    assert collisions == 0
    # reached by the estimate; the true position is within the tolerance plus the filter's few cm of drift
    assert np.linalg.norm(true_xy[-1] - goal) < controller.tolerance + 0.1


@pytest.mark.parametrize("seed", [0, 1])
def test_stops_short_of_the_arena_wall_for_a_goal_beyond_it(seed):
    def goal_of(u):  # 3 m outside the bottom wall, straight below the start
        return np.array([u.world.layout.start[0], -3.0])

    _, true_xy, collisions, reached, controller = _run("EKFSLAM-v0", seed, goal_of, 250)
    assert not reached and collisions == 0
    closest = true_xy[:, 1].min()  # the wall's centre line is y = 0, its surface at 0.05 m
    assert 0.05 + controller.radius < closest < 0.6  # it went right up to the wall, and never touched it


@pytest.mark.parametrize("seed", [0, 3])
def test_stops_at_an_interior_wall_between_rooms(seed):
    """EKFSLAM-Large-v0's rooms: a goal 2 m beyond the interior wall nearest the start (not through a door)."""
    wall = {}

    def goal_of(u):
        start = np.asarray(u.world.layout.start)
        best = None
        for w in np.asarray(u.world.layout.walls)[4:]:  # the first four are the boundary
            a, ab = w[:2], w[2:] - w[:2]
            length = float(np.linalg.norm(ab))
            t = float(np.dot(start[:2] - a, ab)) / length**2
            if 1.0 < t * length < length - 1.0:  # the foot is at least 1 m from the wall's (door) ends
                foot = a + t * ab
                if best is None or np.linalg.norm(foot - start[:2]) < np.linalg.norm(best[0] - start[:2]):
                    best = (foot, w)
        foot, wall["segment"] = best
        return foot + 2.0 * (foot - start[:2]) / np.linalg.norm(foot - start[:2])

    goal, true_xy, collisions, reached, controller = _run("EKFSLAM-Large-v0", seed, goal_of, 300)
    a, b = wall["segment"][:2], wall["segment"][2:]
    side = np.sign((b[0] - a[0]) * (true_xy[:, 1] - a[1]) - (b[1] - a[1]) * (true_xy[:, 0] - a[0]))
    t = np.clip((true_xy - a) @ (b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    distance = np.linalg.norm(a + t[:, None] * (b - a) - true_xy, axis=1)
    assert not reached and collisions == 0
    assert np.all(side == side[0])  # never crossed
    assert 0.05 + controller.radius < distance.min() < 0.6
