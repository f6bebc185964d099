"""The team's simulator (``ekfslam_gym.multi.world``): robots collide, occlude landmarks and beams, and read
each other's positions; the starts are clear."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ekfslam_gym.multi.world import TeamWorld, ray_disc_distances, segment_blocked, team_starts
from ekfslam_gym.sim.layouts import Layout, arena
from ekfslam_gym.sim.odometry import OdometryNoise, WheelOdometryNoise
from ekfslam_gym.sim.robot import RobotParams
from ekfslam_gym.sim.sensor import SensorParams

WALLS = np.array([[0, 0, 20, 0], [20, 0, 20, 20], [20, 20, 0, 20], [0, 20, 0, 0]], dtype=float)


def open_layout(landmarks) -> Layout:
    bounds = np.array([0.0, 0.0, 20.0, 20.0])
    return Layout("arena", WALLS, np.array(landmarks, dtype=float), np.array([5.0, 5.0, 0.0]), bounds, 0.05)


def world(starts, landmarks=((15.0, 15.0),), sensor=None) -> TeamWorld:
    return TeamWorld(
        open_layout(landmarks), np.array(starts, dtype=float), RobotParams(), sensor or SensorParams(),
        OdometryNoise(), WheelOdometryNoise(), 0.1, 2,
    )  # fmt: skip


def test_segment_blocked_against_sampling():
    rng = np.random.default_rng(0)
    start = np.array([1.0, 2.0])
    ends = rng.uniform(-5, 5, (40, 2))
    centres = rng.uniform(-5, 5, (6, 2))
    blocked = segment_blocked(start, ends, centres, 0.4)
    t = np.linspace(0, 1, 20001)[:, None]
    for k, end in enumerate(ends):
        points = start + t * (end - start)
        gaps = np.min(np.hypot(*(points[:, None, :] - centres[None]).transpose(2, 0, 1)), axis=0)
        assert blocked[k] == bool(np.any(gaps < 0.4 - 1e-3)) or abs(gaps.min() - 0.4) < 1e-3


def test_ray_disc_distances_against_marching():
    pose = (0.5, -0.3, 0.7)
    angles = np.arange(16) * (2 * math.pi / 16)
    centres = np.array([[2.0, 1.0], [-1.5, 0.2], [0.4, -3.0]])
    distances = ray_disc_distances(pose, angles, centres, 0.3)
    s = np.linspace(0, 10, 100001)
    for k, a in enumerate(angles):
        points = np.array(pose[:2]) + s[:, None] * np.array([math.cos(pose[2] + a), math.sin(pose[2] + a)])
        inside = np.any(np.hypot(*(points[:, None, :] - centres[None]).transpose(2, 0, 1)) < 0.3, axis=1)
        expected = s[np.argmax(inside)] if inside.any() else math.inf
        assert distances[k] == pytest.approx(expected, abs=2e-4)


def test_a_robot_hides_a_landmark_and_stops_the_scan():
    # robot 1 stands between robot 0 and the landmark, on the line of sight
    team = world([(5.0, 5.0, 0.0), (7.0, 5.0, 0.0)], landmarks=[(9.0, 5.0), (9.0, 8.0)])
    ids, _ = team.sense(0, np.random.default_rng(0))
    assert ids.tolist() == [1]
    alone = world([(5.0, 5.0, 0.0)], landmarks=[(9.0, 5.0), (9.0, 8.0)])
    assert alone.sense(0, np.random.default_rng(0)).ids.tolist() == [0, 1]
    assert team.scan(0)[0] == pytest.approx(2.0 - 0.2)  # beam 0, straight ahead, stops at robot 1's disc
    assert alone.scan(0)[0] == pytest.approx(SensorParams().scan_max_range)


def test_robots_read_each_other_in_view_and_not_through_a_third():
    sensor = SensorParams()
    team = world([(5.0, 5.0, 0.0), (8.0, 5.1, math.pi), (3.0, 5.0, 0.0)])
    draws = [team.read_robots(0, np.random.default_rng(seed)) for seed in range(200)]
    assert all(d.targets.tolist() == [1] for d in draws)  # robot 2 is behind robot 0 (half-circle view)
    z = np.array([d.z[0] for d in draws])
    assert z[:, 0].mean() == pytest.approx(math.hypot(3, 0.1), abs=4 * sensor.range_std / math.sqrt(200))
    assert z[:, 1].mean() == pytest.approx(math.atan2(0.1, 3), abs=4 * sensor.bearing_std / math.sqrt(200))
    assert team.read_robots(1, np.random.default_rng(0)).targets.tolist() == [0]  # robot 0 hides robot 2
    line = world([(2.0, 5.0, 0.0), (4.0, 5.0, 0.0), (6.0, 5.0, 0.0)])
    assert line.read_robots(0, np.random.default_rng(0)).targets.tolist() == [1]


def test_robots_collide_and_do_not_pass_through_each_other():
    """Head-on at full speed the discs meet within one substep's closing travel (2 v_max dt / substeps = 0.1 m,
    pymunk detects contact after integrating), never pass through, and are pushed back to touching."""
    team = world([(5.0, 5.0, 0.0), (6.0, 5.0, math.pi)])
    touched = np.zeros(2, dtype=bool)
    diameter = 2 * RobotParams().radius
    for _ in range(20):
        team.step([(1.0, 0.0), (1.0, 0.0)])
        touched |= team.robot_collided
        (x0, _), (x1, _) = team.positions()
        assert x1 - x0 > diameter - 0.1 - 1e-9
    assert touched.all()
    assert x1 - x0 == pytest.approx(diameter, abs=0.005)
    assert not team.wall_collided.any()


def test_team_starts_are_clear_and_in_a_row_in_the_open():
    layout = arena(np.random.default_rng(3), 30)
    starts = team_starts(layout, 5, 1.0, 4.0, 0.2, np.random.default_rng(0))
    assert starts.shape == (5, 3)
    np.testing.assert_array_equal(starts[0], layout.start)
    gaps = np.hypot(*(starts[:, None, :2] - starts[None, :, :2]).transpose(2, 0, 1))
    assert gaps[~np.eye(5, dtype=bool)].min() >= 0.5
    assert np.all(starts[:, 2] == layout.start[2])


def test_chipmunk_calls_match_pymunks_api():
    """The substeps through Chipmunk's own functions give pymunk's Python API's poses and contacts exactly,
    robots touching each other and the walls included."""
    starts = [(1.0, 1.0, 0.3), (2.0, 1.2, math.pi), (1.5, 2.0, -1.0)]
    fast, slow = world(starts), world(starts)
    slow.robots[0]._chipmunk = None  # the Python API's path
    rng = np.random.default_rng(0)
    touched = np.zeros(3, dtype=bool)
    for _ in range(150):
        commands = [tuple(c) for c in rng.uniform([-1, -2], [1, 2], (3, 2))]
        assert fast.step(commands).tolist() == slow.step(commands).tolist()
        assert fast.robot_collided.tolist() == slow.robot_collided.tolist()
        touched |= fast.robot_collided | fast.wall_collided
        for i in range(3):
            assert fast.pose_tuple(i) == slow.pose_tuple(i)
    assert touched.any()
