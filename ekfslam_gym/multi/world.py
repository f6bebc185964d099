"""The team's simulated world: one pymunk space holding a layout's walls and N robots, each with its odometer
and range-bearing sensor.

It reuses the single-robot simulator's rooms: ``DiffDriveRobot`` bodies (the same joints and the same
substep command as ``DiffDriveRobot.advance``, applied to every robot before each shared ``space.step``), the
odometers of ``sim.odometry`` and the ``RangeBearingSensor``'s kernels. What a team adds:

- robots touch: their discs collide with each other in pymunk (counted per robot, apart from wall contacts);
  head-on at full speed they meet within one substep's closing travel (2 v_max dt / substeps) and are pushed
  back to touching, since pymunk finds a contact after it has moved the bodies;
- robots occlude: a landmark behind another robot's disc is not read, and the wall scan stops at a robot;
- robots read each other: robot i reads robot j's position as (range, bearing) in its own frame, with j's
  identity, when j's centre lies within the sensor's range and field of view and no wall or third robot
  blocks the line of sight (as the MRCLAM robots read each other's barcodes, Leung et al., IJRR 2011), with
  the landmark sensor's noise.

With one robot every draw and every physics call is the single-robot ``World``'s, in the same order. The world
knows nothing of the filter; all randomness comes in through ``rng`` arguments.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pymunk

from .. import compiled
from ..angles import wrap_angle
from ..sim.layouts import Layout
from ..sim.odometry import (
    OdometryNoise,
    VelocityNoise,
    WheelOdometryNoise,
    measure_odometry,
    measure_velocity,
    measure_wheels,
)
from ..sim.robot import WALL_CATEGORY, WALL_COLLISION_TYPE, DiffDriveRobot, RobotParams
from ..sim.sensor import RangeBearingSensor, Readings, SensorParams
from ..sim.world import COLLISION_SLOP
from . import kernels

FIRST_ROBOT_COLLISION_TYPE = 10  # robot i's shape has collision type 10 + i, so contacts are told apart


class RobotReadings(NamedTuple):
    """Robot-to-robot readings of one observer in one control step: ``targets`` (m,) int64 the robots read
    (their identities), ``z`` (m, 2) float64 (range m, bearing rad in (-pi, pi]) of their centres."""

    targets: np.ndarray
    z: np.ndarray


def _count_contact(arbiter: pymunk.Arbiter, space: pymunk.Space, counter: list[int]) -> None:
    """pre_solve callback: one more contact of the counter's robot (module level so it is picklable)."""
    counter[0] += 1


def _count_pair(arbiter: pymunk.Arbiter, space: pymunk.Space, counters: tuple[list[int], list[int]]) -> None:
    counters[0][0] += 1
    counters[1][0] += 1


def segment_blocked(start: np.ndarray, ends: np.ndarray, centres: np.ndarray, radius: float) -> np.ndarray:
    """Whether the segment from ``start`` (2,) to each of ``ends`` (m, 2) passes within ``radius`` m of any of
    ``centres`` (k, 2) (bool (m,)); a centre at an end does not count (the segment ends at it)."""
    ends = np.ascontiguousarray(ends, dtype=np.float64).reshape(-1, 2)
    centres = np.ascontiguousarray(centres, dtype=np.float64).reshape(-1, 2)
    return kernels.segments_blocked(float(start[0]), float(start[1]), ends, centres, float(radius))


def ray_disc_distances(
    pose: tuple[float, float, float], angles: np.ndarray, centres: np.ndarray, radius: float
):
    """Distance (m) along each beam (heading + ``angles``) from the pose's position to the first point of any
    disc of ``radius`` at ``centres`` (k, 2); inf where a beam misses them all."""
    out = np.full(angles.shape[0], np.inf)
    centres = np.ascontiguousarray(centres, dtype=np.float64).reshape(-1, 2)
    kernels.stop_beams_at_discs(pose[0], pose[1], pose[2], angles, centres, float(radius), out)
    return out


class TeamWorld:
    """A layout's walls and landmarks, and ``starts`` (N, 3) robots, with their sensors and odometers.

    Arguments as ``World``'s (robot, sensor and noise parameters shared by every robot; dt the control step, s;
    substeps physics steps per control step). ``v_max * dt / substeps`` must not exceed half the robot's radius.
    """

    def __init__(
        self,
        layout: Layout,
        starts: np.ndarray,
        robot: RobotParams,
        sensor: SensorParams,
        odometry_noise: OdometryNoise,
        wheel_noise: WheelOdometryNoise,
        dt: float,
        substeps: int,
        velocity_noise: VelocityNoise | None = None,
    ) -> None:
        starts = np.asarray(starts, dtype=np.float64).reshape(-1, 3)
        self.layout = layout
        self.n_robots = starts.shape[0]
        self.robot_params = robot
        self.sensor_params = sensor
        self.odometry_noise = odometry_noise
        self.wheel_noise = wheel_noise
        self.velocity_noise = velocity_noise if velocity_noise is not None else VelocityNoise()
        self.dt = float(dt)
        self.substeps = int(substeps)
        self._h = self.dt / self.substeps
        if robot.v_max * self._h > 0.5 * robot.radius:
            raise ValueError(
                f"v_max * dt / substeps = {robot.v_max * self._h:.3g} m exceeds half the robot radius "
                f"({0.5 * robot.radius} m): raise substeps so no robot can tunnel through walls"
            )
        self.space = pymunk.Space()
        self.space.collision_slop = COLLISION_SLOP
        wall_filter = pymunk.ShapeFilter(categories=WALL_CATEGORY)
        for x1, y1, x2, y2 in layout.walls:
            wall = pymunk.Segment(self.space.static_body, (x1, y1), (x2, y2), layout.wall_radius)
            wall.friction = 1.0
            wall.elasticity = 0.0
            wall.collision_type = WALL_COLLISION_TYPE
            wall.filter = wall_filter
            self.space.add(wall)
        self.robots: list[DiffDriveRobot] = []
        self._wall_contacts = [[0] for _ in range(self.n_robots)]
        self._robot_contacts = [[0] for _ in range(self.n_robots)]
        for i, start in enumerate(starts):
            robot_i = DiffDriveRobot(self.space, (start[0], start[1], start[2]), robot, self._h)
            robot_i.shape.collision_type = FIRST_ROBOT_COLLISION_TYPE + i
            self.space.on_collision(
                FIRST_ROBOT_COLLISION_TYPE + i, WALL_COLLISION_TYPE, pre_solve=_count_contact,
                data=self._wall_contacts[i],
            )  # fmt: skip
            self.robots.append(robot_i)
        for i in range(self.n_robots):
            for j in range(i + 1, self.n_robots):
                self.space.on_collision(
                    FIRST_ROBOT_COLLISION_TYPE + i, FIRST_ROBOT_COLLISION_TYPE + j, pre_solve=_count_pair,
                    data=(self._robot_contacts[i], self._robot_contacts[j]),
                )  # fmt: skip
        self.sensor = RangeBearingSensor(layout.landmarks, layout.walls, layout.wall_radius, sensor)
        self._half_fov = 0.5 * sensor.fov
        self._poses = [r.pose() for r in self.robots]
        self._prev_poses = list(self._poses)
        self._trace_substeps = not wheel_noise.slide_sensed
        self._traces: list[list[tuple[float, float, float]]] = [[p] for p in self._poses]
        self.wall_collided = np.zeros(self.n_robots, dtype=bool)
        self.robot_collided = np.zeros(self.n_robots, dtype=bool)
        self._commands: list[list[tuple[float, float]]] = [[] for _ in range(self.n_robots)]
        # scratch for the robot-to-robot readings: the kernel writes the visible ones here
        self._ids = np.empty(self.n_robots, dtype=np.int64)
        self._z = np.empty((self.n_robots, 2))

    # --- physics -------------------------------------------------------------------------------------------
    def step(self, commands: list[tuple[float, float]]) -> np.ndarray:
        """Drive every robot for one control step at its (forward speed m/s, turn rate rad/s), clipped to the
        robot's limits. Returns which robots touched a wall (bool (N,)); ``robot_collided`` says which touched
        another robot. Each substep sets every robot's command as ``DiffDriveRobot.advance`` does, then steps
        the shared space once."""
        rp = self.robot_params
        clipped = []
        for i, (v, omega) in enumerate(commands):
            v, omega = float(v), float(omega)
            if not (math.isfinite(v) and math.isfinite(omega)):
                raise ValueError(f"robot {i}'s command must be finite, got v={v!r}, omega={omega!r}")
            command = (min(max(v, -rp.v_max), rp.v_max), min(max(omega, -rp.omega_max), rp.omega_max))
            clipped.append(command)
            self._commands[i].append(command)
        for counter in self._wall_contacts + self._robot_contacts:
            counter[0] = 0
        h = self._h
        traces = [[p] for p in self._poses] if self._trace_substeps else None
        calls = self.robots[0]._chipmunk
        if calls is not None and calls[0] is self.space:
            self._advance_chipmunk(calls, clipped, h, traces)
        else:
            self._advance_pymunk(clipped, h, traces)
        self._prev_poses = self._poses
        self._poses = [r.pose() for r in self.robots]
        if traces is not None:
            self._traces = traces
        for i in range(self.n_robots):
            self.wall_collided[i] = self._wall_contacts[i][0] > 0
            self.robot_collided[i] = self._robot_contacts[i][0] > 0
        return self.wall_collided

    def _advance_pymunk(self, clipped, h, traces) -> None:
        """The substeps through pymunk's Python API: every robot's command as ``DiffDriveRobot.advance`` sets
        it, then one step of the shared space."""
        for robot, (_, omega) in zip(self.robots, clipped):
            robot.control.angular_velocity = omega
        for _ in range(self.substeps):
            for robot, (v, omega) in zip(self.robots, clipped):
                body = robot.body
                heading = body.angle + (body.angular_velocity + 0.5 * omega) * h
                robot.control.velocity = (v * math.cos(heading), v * math.sin(heading))
            self.space.step(h)
            if traces is not None:
                for robot, trace in zip(self.robots, traces):
                    p = robot.body.position
                    trace.append((p.x, p.y, robot.body.angle))

    def _advance_chipmunk(self, calls, clipped, h, traces) -> None:
        """``_advance_pymunk`` through Chipmunk's own functions, as ``DiffDriveRobot.advance`` calls them (the
        same C calls in the same order, without pymunk's Python layer)."""
        (
            _,
            step,
            handle,
            get_angle,
            get_angular_velocity,
            set_velocity,
            set_angular_velocity,
            _,
            _,
            position,
        ) = calls
        handles = [(robot._chipmunk[7], robot._chipmunk[8]) for robot in self.robots]
        for (c, _), (_, omega) in zip(handles, clipped):
            set_angular_velocity(c, omega)
        for _ in range(self.substeps):
            for (c, b), (v, omega) in zip(handles, clipped):
                heading = get_angle(b) + (get_angular_velocity(b) + 0.5 * omega) * h
                set_velocity(c, (v * math.cos(heading), v * math.sin(heading)))
            step(handle, h)
            if traces is not None:
                for (_, b), trace in zip(handles, traces):
                    p = position(b)
                    trace.append((p.x, p.y, get_angle(b)))

    def pose_tuple(self, i: int) -> tuple[float, float, float]:
        """Robot i's true pose (x m, y m, theta rad), theta unwrapped."""
        return self._poses[i]

    def pose(self, i: int) -> np.ndarray:
        """Robot i's true pose (3,) float64, theta in (-pi, pi]."""
        x, y, theta = self._poses[i]
        return np.array([x, y, wrap_angle(theta)])

    @property
    def poses(self) -> np.ndarray:
        """Every robot's true pose (N, 3), theta in (-pi, pi]."""
        return np.array([self.pose(i) for i in range(self.n_robots)])

    def positions(self) -> np.ndarray:
        """Every robot's true position (N, 2), m."""
        return np.array([p[:2] for p in self._poses])

    # --- odometry ------------------------------------------------------------------------------------------
    def _contact_travel(self, i: int) -> float:
        if not self.wall_collided[i]:
            return 0.0
        return max(abs(v) for v, _ in self._commands[i][-2:]) * self.dt

    def odometry(self, i: int, model: str, rng: np.random.Generator):
        """Robot i's last control step as its odometer reads it: ``model`` ``wheels`` (wheel travels and slip,
        ``World.wheel_odometry``), ``odometry`` (rot1, trans, rot2) or ``velocity`` (v, omega)."""
        if model == "wheels":
            trace = self._traces[i] if self._trace_substeps else (self._prev_poses[i], self._poses[i])
            return measure_wheels(trace, self.wheel_noise, self._contact_travel(i), rng)
        if model == "odometry":
            return measure_odometry(self._prev_poses[i], self._poses[i], self.odometry_noise, rng)
        return measure_velocity(self._prev_poses[i], self._poses[i], self.dt, self.velocity_noise, rng)

    # --- sensing -------------------------------------------------------------------------------------------
    def _others(self, i: int) -> np.ndarray:
        """The other robots' true positions (N - 1, 2)."""
        return np.array([p[:2] for j, p in enumerate(self._poses) if j != i], dtype=np.float64).reshape(-1, 2)

    def sense(self, i: int, rng: np.random.Generator) -> Readings:
        """Robot i's noisy landmark readings (ids ordered, (range, bearing)), the landmarks hidden by a wall or
        another robot left out; the draws of ``RangeBearingSensor.sense`` (detection, then noise)."""
        pose = self._poses[i]
        ids, z = self.sensor.true_readings(pose)
        if self.n_robots > 1 and ids.shape[0]:
            visible = ~kernels.segments_blocked(
                pose[0], pose[1], self.layout.landmarks[ids], self._others(i), self.robot_params.radius
            )
            ids, z = ids[visible], z[visible]
        p = self.sensor_params
        if p.detection_prob < 1.0 and z.shape[0]:
            keep = rng.random(z.shape[0]) < p.detection_prob
            ids, z = ids[keep], z[keep]
        if z.shape[0]:
            compiled.add_reading_noise(z, rng.standard_normal(z.shape), p.range_std, p.bearing_std)
        return Readings(np.ascontiguousarray(ids), np.ascontiguousarray(z))

    def read_robots(self, i: int, rng: np.random.Generator) -> RobotReadings:
        """Robot i's noisy readings of its teammates' positions: those within the sensor's range and field of
        view whose line of sight no wall and no third robot blocks, in order of identity."""
        if self.n_robots == 1:
            return RobotReadings(np.empty(0, dtype=np.int64), np.empty((0, 2)))
        pose = self._poses[i]
        positions = self.positions()
        p = self.sensor_params
        m = compiled.visible_landmarks(
            pose[0], pose[1], pose[2], positions, self.layout.walls, self.layout.wall_radius,
            max(p.min_range, 1e-9), p.max_range, self._half_fov, self._ids, self._z,
        )  # fmt: skip
        targets, z = self._ids[:m].copy(), self._z[:m].copy()
        keep = targets != i
        targets, z = targets[keep], z[keep]
        if targets.shape[0] and self.n_robots > 2:
            visible = np.ones(targets.shape[0], dtype=bool)
            for k, target in enumerate(targets):
                third = np.array([positions[j] for j in range(self.n_robots) if j not in (i, target)])
                visible[k] = not segment_blocked(
                    positions[i], positions[target][None, :], third, self.robot_params.radius
                )[0]
            targets, z = targets[visible], z[visible]
        if p.detection_prob < 1.0 and z.shape[0]:
            keep = rng.random(z.shape[0]) < p.detection_prob
            targets, z = targets[keep], z[keep]
        if z.shape[0]:
            compiled.add_reading_noise(z, rng.standard_normal(z.shape), p.range_std, p.bearing_std)
        return RobotReadings(np.ascontiguousarray(targets), np.ascontiguousarray(z))

    def scan(self, i: int) -> np.ndarray:
        """Robot i's wall scan (n_beams,) in m, clipped at scan_max_range; another robot's disc stops a beam
        as a wall does."""
        pose = self._poses[i]
        out = self.sensor.scan(pose)
        if self.n_robots > 1:
            kernels.stop_beams_at_discs(
                pose[0],
                pose[1],
                pose[2],
                self.sensor.beam_angles,
                self._others(i),
                self.robot_params.radius,
                out,
            )
        return out


def team_starts(
    layout: Layout, n_robots: int, spacing: float, spread: float, radius: float, rng: np.random.Generator
) -> np.ndarray:
    """Start poses (N, 3): robot 0 at the layout's start, the others in a row across its heading, ``spacing``
    m apart (alternating left and right), all facing the same way, as a team set down together. Where a wall
    is in the way a robot is placed instead at a uniform draw within ``spread`` m of robot 0, clear of the
    walls and of the robots already placed, with a straight free path to robot 0 (no draw is made otherwise).
    """
    start = np.asarray(layout.start, dtype=np.float64)
    walls, bounds = layout.walls, layout.bounds
    clearance = radius + layout.wall_radius + 0.1
    starts = [start]

    def free(xy: np.ndarray) -> bool:
        if not (bounds[0] + clearance <= xy[0] <= bounds[2] - clearance):
            return False
        if not (bounds[1] + clearance <= xy[1] <= bounds[3] - clearance):
            return False
        if any(math.hypot(xy[0] - s[0], xy[1] - s[1]) < 2.0 * radius + 0.1 for s in starts):
            return False
        line = start[:2] + np.linspace(0.0, 1.0, 16)[:, None] * (xy - start[:2])
        return bool(compiled.min_wall_distance(np.ascontiguousarray(line), walls).min() >= clearance)

    left = np.array([-math.sin(start[2]), math.cos(start[2])])
    for k in range(1, n_robots):
        side = 1.0 if k % 2 else -1.0
        xy = start[:2] + side * ((k + 1) // 2) * spacing * left
        if not free(xy):
            for _ in range(500):
                r, a = spread * math.sqrt(rng.random()), rng.uniform(-math.pi, math.pi)
                xy = start[:2] + r * np.array([math.cos(a), math.sin(a)])
                if free(xy):
                    break
            else:
                raise ValueError(
                    f"found no start for robot {k} within team.start_spread = {spread} m of robot 0: "
                    "use a larger spread or fewer robots"
                )
        starts.append(np.array([xy[0], xy[1], start[2]]))
    return np.array(starts)
