"""The simulated world: determinism, walls (collisions, no tunnelling, occlusion), readings, pickling."""

from __future__ import annotations

import copy
import hashlib
import math
import pickle
import subprocess
import sys

import numpy as np
import pymunk
import pytest

from ekfslam_gym.sim import Layout, RobotParams, SensorParams, World, make_layout
from ekfslam_gym.sim.geometry import min_wall_distance, wrap_angle
from ekfslam_gym.sim.robot import WALL_CATEGORY

BOX = [[0, 0, 10, 0], [10, 0, 10, 10], [10, 10, 0, 10], [0, 10, 0, 0]]


def _layout(walls: list, landmarks: list, start: tuple[float, float, float]) -> Layout:
    return Layout("test", np.array(walls, dtype=float), np.array(landmarks, dtype=float).reshape(-1, 2),
                  np.array(start), np.array([0.0, 0.0, 10.0, 10.0]), 0.05)  # fmt: skip


def _rollout(seed: int, n_steps: int, layout_name: str = "rooms") -> list[bytes]:
    """Everything the env would see over a random drive, as bytes, rebuilding the world on a collision."""
    rng = np.random.default_rng(seed)
    world = World(make_layout(layout_name, rng, 30))
    out = []
    for k in range(n_steps):
        if k % 10 == 0:
            command = rng.uniform((-1.0, -2.0), (1.0, 2.0))
        collided = world.step(*command)
        odometry = world.odometry(rng)
        readings = world.sense(rng)
        out.append(b"".join(a.tobytes() for a in (world.pose, odometry.u, odometry.cov, readings.ids,
                                                   readings.z, world.scan(), np.array([collided]))))  # fmt: skip
        if collided:
            world = World(make_layout(layout_name, rng, 30))
    return out


def test_same_seed_gives_bit_identical_rollouts() -> None:
    a = _rollout(0, 400)
    assert a == _rollout(0, 400)
    assert a != _rollout(1, 400)


def test_rollouts_are_bit_identical_across_processes() -> None:
    code = (
        "import hashlib, sys; from tests.sim.test_world import _rollout; "
        "print(hashlib.sha256(b''.join(_rollout(3, 200, 'loop'))).hexdigest())"
    )
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert child.stdout.strip() == hashlib.sha256(b"".join(_rollout(3, 200, "loop"))).hexdigest()


def _drive_until_contact(world: World, rng: np.random.Generator) -> None:
    """Random driving until the robot is pressed against a wall (its contact state is mid-solve)."""
    for _ in range(2000):
        if world.step(1.0, rng.uniform(-0.5, 0.5)):
            for _ in range(3):
                world.step(1.0, 0.0)
            assert world.collided
            return
    raise AssertionError("never touched a wall")


@pytest.mark.parametrize("copier", [lambda w: pickle.loads(pickle.dumps(w)), copy.deepcopy])
def test_pickle_round_trip_mid_drive_continues_identically(copier) -> None:
    rng = np.random.default_rng(0)
    world = World(make_layout("rooms", rng, 30))
    _drive_until_contact(world, rng)
    twin = copier(world)
    twin_rng = copy.deepcopy(rng)
    assert twin.n_steps == world.n_steps and np.array_equal(twin.pose, world.pose)
    for k in range(300):
        command = rng.uniform((-1.0, -2.0), (1.0, 2.0))
        assert np.array_equal(command, twin_rng.uniform((-1.0, -2.0), (1.0, 2.0)))
        assert world.step(*command) == twin.step(*command)
        assert np.array_equal(world.pose, twin.pose), k
        assert np.array_equal(world.odometry(rng).u, twin.odometry(twin_rng).u)
        a, b = world.sense(rng), twin.sense(twin_rng)
        assert np.array_equal(a.ids, b.ids) and np.array_equal(a.z, b.z)
        assert np.array_equal(world.scan(), twin.scan())


def test_direct_chipmunk_calls_match_pymunks_python_api_exactly() -> None:
    """The robot drives through Chipmunk's functions directly (speed); pymunk's Python API must agree bit for
    bit, through wall contacts included."""
    fast, slow = (World(make_layout("rooms", np.random.default_rng(4), 30)) for _ in range(2))
    assert fast.robot._chipmunk is not None, "this pymunk no longer exposes Chipmunk's functions"
    slow.robot._chipmunk = None
    rng = np.random.default_rng(4)
    contacts = 0
    for k in range(600):
        if k % 10 == 0:
            command = rng.uniform((-1.0, -2.0), (1.0, 2.0))
        hit = fast.step(*command)
        assert hit == slow.step(*command)
        assert fast.pose_tuple == slow.pose_tuple, k
        contacts += hit
    assert contacts > 0  # the drive exercised the contact solver


def test_collision_is_reported_when_driving_into_a_wall() -> None:
    world = World(_layout(BOX, [], (5.0, 5.0, 0.0)))
    flags = [world.step(1.0, 0.0) for _ in range(60)]
    first = flags.index(True)
    # 5 m to the wall minus radius 0.2 and wall radius 0.05 at 1 m/s and 0.1 s a step (one substep of lag)
    assert 45 <= first <= 48
    assert not any(flags[:first]) and all(flags[first:])
    world.step(-1.0, 0.0)  # backing away: the first substep still carries the old velocity (one substep lag)
    assert not any(world.step(-1.0, 0.0) for _ in range(5))


@pytest.mark.parametrize("approach", [0.0, 0.3, 0.8, 1.2])
@pytest.mark.parametrize(("v_max", "substeps"), [(1.0, 2), (2.0, 4), (4.0, 8)])
def test_the_robot_never_passes_through_a_wall(approach: float, v_max: float, substeps: int) -> None:
    """Flat out into a thin wall across the box at various angles, turning, for 100 steps."""
    wall = [5.0, 0.0, 5.0, 10.0]
    world = World(_layout([*BOX, wall], [], (3.0, 5.0, approach)), robot=RobotParams(v_max=v_max),
                  substeps=substeps)  # fmt: skip
    contact = 0.2 + 0.05
    touched = False
    for k in range(100):
        touched |= world.step(2.0 * v_max, 0.3 * math.sin(0.2 * k))
        x, y, _ = world.pose
        assert x < 5.0  # never beyond the wall's centre line
        assert min_wall_distance(np.array([[x, y]]), np.array([wall]))[0] > contact - 0.06
    assert touched


def test_commands_are_clipped_and_non_finite_ones_rejected() -> None:
    world = World(_layout(BOX, [], (2.0, 5.0, 0.0)))
    for _ in range(5):
        world.step(100.0, 0.0)
    assert world.odometry(np.random.default_rng(0)).u_true[1] == pytest.approx(0.1)  # v_max * dt
    pose, n = world.pose, world.n_steps
    for bad in [(float("nan"), 0.0), (0.0, float("inf"))]:
        with pytest.raises(ValueError, match="finite"):
            world.step(*bad)
    assert np.array_equal(world.pose, pose) and world.n_steps == n


def test_a_landmark_behind_a_wall_is_never_read() -> None:
    # landmark 0 straight ahead behind a wall, landmark 1 beside it in the open; both within range and FOV
    layout = _layout([*BOX, [5.0, 3.0, 5.0, 5.5]], [[7.0, 4.0], [7.0, 7.5]], (3.0, 4.0, 0.0))
    world = World(layout)
    rng = np.random.default_rng(0)
    for _ in range(200):
        assert world.sense(rng).ids.tolist() == [1]
    # from the other side of the wall's end, it is seen
    world = World(_layout([*BOX, [5.0, 3.0, 5.0, 5.5]], [[7.0, 4.0], [7.0, 7.5]], (3.0, 8.0, -0.5)))
    assert world.sense(rng).ids.tolist() == [0, 1]


def test_readings_over_a_random_drive() -> None:
    """Range and FOV respected, never through a wall (pymunk's own query), ids sorted, bearings wrapped,
    and the reading noise has the configured standard deviations."""
    params = SensorParams(min_range=0.5, max_range=5.0, fov=math.radians(120))
    rng = np.random.default_rng(1)
    world = World(make_layout("rooms", rng, 40), sensor=params)
    walls_only = pymunk.ShapeFilter(mask=WALL_CATEGORY)
    errors = []
    n_read = 0
    for k in range(1500):
        if k % 15 == 0:
            command = rng.uniform((-0.5, -2.0), (1.0, 2.0))
        if world.step(*command):
            world = World(make_layout("rooms", rng, 40), sensor=params)
            continue
        exact = world.true_readings()
        noisy = world.sense(rng)
        assert np.array_equal(exact.ids, noisy.ids)
        assert (
            noisy.ids.dtype == np.int64
            and noisy.z.dtype == np.float64
            and noisy.z.shape == (len(noisy.ids), 2)
        )
        assert np.all(np.diff(noisy.ids) > 0)
        assert np.all((exact.z[:, 0] >= 0.5) & (exact.z[:, 0] <= 5.0))
        assert np.all(np.abs(exact.z[:, 1]) <= math.radians(60))
        assert np.all((noisy.z[:, 1] > -math.pi) & (noisy.z[:, 1] <= math.pi))
        x, y, theta = world.pose
        for i, (r, b) in zip(exact.ids, exact.z):
            lx, ly = world.layout.landmarks[i]
            assert r == pytest.approx(math.hypot(lx - x, ly - y))
            assert b == pytest.approx(wrap_angle(math.atan2(ly - y, lx - x) - theta))
            assert world.space.segment_query_first((x, y), (lx, ly), 0.0, walls_only) is None
        diff = noisy.z - exact.z
        diff[:, 1] = [wrap_angle(d) for d in diff[:, 1]]
        errors.extend(diff.tolist())
        n_read += len(exact.ids)
    errors = np.array(errors)
    assert n_read > 1000
    assert np.std(errors[:, 0]) == pytest.approx(params.range_std, rel=0.08)
    assert np.std(errors[:, 1]) == pytest.approx(params.bearing_std, rel=0.08)


def test_scan_measures_the_distance_to_the_walls() -> None:
    world = World(_layout(BOX, [], (3.0, 4.0, 0.0)), sensor=SensorParams(n_beams=4, scan_max_range=5.0))
    # ahead 7 m (clipped to 5), left 6 m (clipped), behind 3 m, right 4 m; minus the wall radius
    assert np.allclose(world.scan(), [5.0, 5.0, 2.95, 3.95])
    assert world.sensor_params.cov.shape == (2, 2)


@pytest.mark.parametrize(
    ("make_kwargs", "match"),
    [
        (lambda: {"dt": 0.0}, "dt"),
        (lambda: {"substeps": 0}, "substeps"),
        (lambda: {"robot": RobotParams(v_max=4.0)}, "tunnel"),
        (lambda: {"robot": RobotParams(radius=-1.0)}, "radius"),
        (lambda: {"sensor": SensorParams(max_range=0.1)}, "max_range"),
        (lambda: {"sensor": SensorParams(fov=7.0)}, "fov"),
    ],
)
def test_bad_parameters_raise(make_kwargs, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        World(_layout(BOX, [], (5.0, 5.0, 0.0)), **make_kwargs())


def test_start_overlapping_a_wall_raises() -> None:
    with pytest.raises(ValueError, match="overlaps a wall"):
        World(_layout(BOX, [], (0.1, 5.0, 0.0)))


@pytest.mark.parametrize(
    "sensor",
    [SensorParams(), SensorParams(detection_prob=0.8), SensorParams(clutter_rate=0.5)],
    ids=["ideal", "misses", "clutter"],
)
def test_wheel_odometry_and_readings_equal_the_two_separate_readings(sensor: SensorParams) -> None:
    """The fused call (one draw, one kernel where the sensor is ideal) gives the very values of
    ``wheel_odometry`` then ``sense`` from the same generator, over a drive with wall contacts and with steps
    that read no landmark."""
    layout = make_layout("rooms", np.random.default_rng(7), 30)
    fused, separate = World(layout, sensor=sensor), World(layout, sensor=sensor)
    rng_fused, rng_separate = np.random.default_rng(3), np.random.default_rng(3)
    drive = np.random.default_rng(5)
    empty = contacts = 0
    for k in range(1500):
        if k % 20 == 0:  # held commands, mostly forward, reach the walls
            v, omega = drive.uniform((0.2, -1.0), (1.0, 1.0)) * (
                fused.robot_params.v_max,
                fused.robot_params.omega_max,
            )
        contacts += fused.step(v, omega)
        separate.step(v, omega)
        odometry, readings = fused.wheel_odometry_and_readings(rng_fused)
        expected_odometry, expected_readings = (
            separate.wheel_odometry(rng_separate),
            separate.sense(rng_separate),
        )
        for got, want in zip((*odometry, *readings), (*expected_odometry, *expected_readings), strict=True):
            np.testing.assert_array_equal(got, want)
        empty += readings.ids.size == 0
    assert contacts > 0 and empty > 0  # both kinds of step were exercised
    assert rng_fused.bit_generator.state == rng_separate.bit_generator.state
