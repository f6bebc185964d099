"""The simulated world: a pymunk space holding a layout's walls and the robot, the sensor and the odometer.

The env builds a new ``World`` at every reset (nothing is teleported) and composes it with the filter; the world
knows nothing of the filter. All randomness comes in through the ``rng`` arguments of the noisy readings; the
physics itself is deterministic, so a world is a pure function of its layout, parameters and command history.

Pickling: pymunk 7 pickles a space but not its solver's hidden state (the bodies' bias velocities and the
joints' accumulated impulses used for warm starting), so a space unpickled while the robot touches a wall
continues differently (measured on a prototype: 28 of 30 mid-contact pickles diverged). A world therefore
pickles its layout, parameters and the commands since it was built (16 bytes a step), and unpickling rebuilds
the space and replays them (about 7 µs a step, 20 µs in contact with a wall), then checks that the pose
matches bit for bit.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pymunk

from .. import compiled
from ..angles import wrap_angle
from .layouts import Layout
from .odometry import (
    OdometryNoise,
    OdometryReading,
    VelocityNoise,
    VelocityReading,
    WheelOdometryNoise,
    WheelOdometryReading,
    measure_odometry,
    measure_velocity,
    measure_wheels,
)
from .robot import ROBOT_COLLISION_TYPE, WALL_CATEGORY, WALL_COLLISION_TYPE, DiffDriveRobot, RobotParams
from .sensor import RangeBearingSensor, Readings, SensorParams

COLLISION_SLOP = 0.002  # m of overlap pymunk allows before pushing apart (its default, 0.1, suits pixels)


def _count_contact(arbiter: pymunk.Arbiter, space: pymunk.Space, counter: list[int]) -> None:
    """pre_solve callback: one more robot-wall contact in this substep (module level so it is picklable)."""
    counter[0] += 1


class World:
    """A layout's walls and landmarks, the robot at the layout's start pose, its sensor and odometry.

    Arguments: layout; robot, sensor, odometry_noise, velocity_noise (defaults if None); dt, the control step
    (s); substeps, physics steps per control step; wheel_noise (keyword; default if None), the wheel odometry. ``robot.v_max * dt / substeps`` must not exceed half the
    robot's radius, so no substep can carry the robot through a wall.
    """

    def __init__(
        self,
        layout: Layout,
        robot: RobotParams | None = None,
        sensor: SensorParams | None = None,
        odometry_noise: OdometryNoise | None = None,
        velocity_noise: VelocityNoise | None = None,
        dt: float = 0.1,
        substeps: int = 2,
        *,
        wheel_noise: WheelOdometryNoise | None = None,
    ) -> None:
        self.layout = layout
        self.robot_params = robot if robot is not None else RobotParams()
        self.sensor_params = sensor if sensor is not None else SensorParams()
        self.odometry_noise = odometry_noise if odometry_noise is not None else OdometryNoise()
        self.velocity_noise = velocity_noise if velocity_noise is not None else VelocityNoise()
        self.wheel_noise = wheel_noise if wheel_noise is not None else WheelOdometryNoise()
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be finite and > 0 s, got {dt!r}")
        if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 1:
            raise ValueError(f"substeps must be an int >= 1, got {substeps!r}")
        self.dt = float(dt)
        self.substeps = substeps
        self._h = self.dt / substeps
        rp = self.robot_params
        if rp.v_max * self._h > 0.5 * rp.radius:
            raise ValueError(
                f"v_max * dt / substeps = {rp.v_max * self._h:.3g} m exceeds half the robot radius "
                f"({0.5 * rp.radius} m): raise substeps so the robot cannot tunnel through walls"
            )
        start = layout.start
        clearance = (
            float(compiled.min_wall_distance(start[None, :2], layout.walls)[0])
            if len(layout.walls)
            else math.inf
        )
        if clearance < rp.radius + layout.wall_radius:
            raise ValueError(f"the robot (radius {rp.radius} m) overlaps a wall at the layout's start pose")

        self.space = pymunk.Space()
        self.space.collision_slop = COLLISION_SLOP
        wall_filter = pymunk.ShapeFilter(categories=WALL_CATEGORY)
        for x1, y1, x2, y2 in layout.walls:
            wall = pymunk.Segment(self.space.static_body, (x1, y1), (x2, y2), layout.wall_radius)
            wall.friction = 1.0  # pymunk multiplies the two; the robot's friction sets the pair's
            wall.elasticity = 0.0
            wall.collision_type = WALL_COLLISION_TYPE
            wall.filter = wall_filter
            self.space.add(wall)
        self.robot = DiffDriveRobot(self.space, (start[0], start[1], start[2]), rp, self._h)
        self._contacts = [0]
        self.space.on_collision(
            ROBOT_COLLISION_TYPE, WALL_COLLISION_TYPE, pre_solve=_count_contact, data=self._contacts
        )
        self.sensor = RangeBearingSensor(
            layout.landmarks, layout.walls, layout.wall_radius, self.sensor_params
        )

        self._pose = self.robot.pose()
        self._prev_pose = self._pose
        # the poses after each substep of the last step, its start first (see ``wheel_odometry``)
        self._trace_substeps = not self.wheel_noise.slide_sensed
        self._trace: list[tuple[float, float, float]] | None = [self._pose] * (substeps + 1)
        self._collided = False
        self._commands: list[tuple[float, float]] = []

    # --- physics -------------------------------------------------------------------------------------------
    def step(self, v: float, omega: float) -> bool:
        """Drive for one control step at forward speed v (m/s) and turn rate omega (rad/s).

        Commands are clipped to +-v_max and +-omega_max; a non-finite command raises ValueError and changes
        nothing. The body answers one substep late (see ``DiffDriveRobot.advance``). Returns True if the
        robot touched a wall (a pymunk contact) at any substep; a contact costs ~6 µs more per substep.
        """
        v = float(v)
        omega = float(omega)
        if not (math.isfinite(v) and math.isfinite(omega)):
            raise ValueError(f"the command must be finite, got v={v!r}, omega={omega!r}")
        rp = self.robot_params
        v = min(max(v, -rp.v_max), rp.v_max)
        omega = min(max(omega, -rp.omega_max), rp.omega_max)
        self._commands.append((v, omega))
        return self._advance(v, omega)

    def _advance(self, v: float, omega: float) -> bool:
        """One control step with an already clipped command."""
        self._contacts[0] = 0
        robot = self.robot
        # the poses after each substep (5 us a step), only for wheel odometry that integrates them
        trace = [self._pose] if self._trace_substeps else None
        robot.advance(self.space, v, omega, self._h, self.substeps, trace)
        self._prev_pose = self._pose
        self._pose = robot.pose()
        self._trace = trace
        self._collided = self._contacts[0] > 0
        return self._collided

    @property
    def pose(self) -> np.ndarray:
        """True pose (3,) float64: (x m, y m, theta rad in (-pi, pi])."""
        x, y, theta = self._pose
        return np.array([x, y, wrap_angle(theta)])

    @property
    def pose_tuple(self) -> tuple[float, float, float]:
        """True pose (x m, y m, theta rad) as the immutable tuple the world keeps, theta unwrapped (continuous
        over the episode): ``pose`` without building an array, for callers on the env's hot path."""
        return self._pose

    @property
    def last_motion(self) -> tuple[np.ndarray, np.ndarray]:
        """True poses (3,) before and after the last step, headings unwrapped (their difference is the turn)."""
        return np.array(self._prev_pose), np.array(self._pose)

    @property
    def collided(self) -> bool:
        """Whether the robot touched a wall during the last step."""
        return self._collided

    @property
    def n_steps(self) -> int:
        """Control steps taken since the world was built."""
        return len(self._commands)

    # --- odometry ------------------------------------------------------------------------------------------
    def odometry(self, rng: np.random.Generator) -> OdometryReading:
        """The last step's true motion as noisy (rot1, trans, rot2) with its covariance M (3, 3).

        Draws 3 normals from ``rng``; call once per step. Before the first step the motion is zero.
        """
        return measure_odometry(self._prev_pose, self._pose, self.odometry_noise, rng)

    def velocity_odometry(self, rng: np.random.Generator) -> VelocityReading:
        """The last step's motion as noisy (v, omega) with its covariance (2, 2); approximate, see
        ``odometry.velocity_from_motion``. Draws 2 normals from ``rng``."""
        return measure_velocity(self._prev_pose, self._pose, self.dt, self.velocity_noise, rng)

    def wheel_odometry(self, rng: np.random.Generator) -> WheelOdometryReading:
        """The last step as wheel odometry: noisy wheel travels (left, right) and sideways slip, with the
        covariance diag(std^2) (3, 3); see ``WheelOdometryNoise``. A step in contact with a wall (the bumper:
        ``collided``) has a slip variance growing with the commanded travel max(|v_previous|, |v|) dt (the body
        answers a command one substep late). Draws 3 normals from ``rng``; call once per step."""
        trace = self._trace if self._trace_substeps else (self._prev_pose, self._pose)
        return measure_wheels(trace, self.wheel_noise, self._contact_travel(), rng)

    def wheel_odometry_and_readings(self, rng: np.random.Generator) -> tuple[WheelOdometryReading, Readings]:
        """``(wheel_odometry(rng), sense(rng))``: the same draws and values, in one compiled call and one draw
        of 3 + 2 m normals where the slide is sensed and the sensor neither misses nor clutters (the defaults;
        a Generator's normals do not depend on how a draw is split); otherwise those two calls."""
        if self._trace_substeps or not self.sensor.ideal:
            return self.wheel_odometry(rng), self.sense(rng)
        ids, z = readings = self.sensor.true_readings(self._pose)
        normals = rng.standard_normal(3 + 2 * z.shape[0])
        reading = WheelOdometryReading(np.empty(3), np.zeros((3, 3)), np.empty(3))
        x0, y0, theta0 = self._prev_pose
        x1, y1, theta1 = self._pose
        noise, sensor = self.wheel_noise, self.sensor_params
        compiled.measure_step(
            x0, y0, theta0, x1, y1, theta1, noise.wheel_base, self._contact_travel(), noise.vector, normals,
            reading.u, reading.cov, reading.u_true, z, sensor.range_std, sensor.bearing_std,
        )  # fmt: skip
        return reading, readings

    def _contact_travel(self) -> float:
        """The commanded travel (m) of the last step if it touched a wall, else 0 (``WheelOdometryNoise``)."""
        if not self._collided:
            return 0.0
        return max(abs(v) for v, _ in self._commands[-2:]) * self.dt

    # --- sensing -------------------------------------------------------------------------------------------
    def sense(self, rng: np.random.Generator) -> Readings:
        """Noisy landmark readings from the current true pose (ids (m,) int64, z (m, 2)), ordered by id."""
        return self.sensor.sense(self._pose, rng)

    def true_readings(self) -> Readings:
        """Noise-free landmark readings from the current true pose."""
        return self.sensor.true_readings(self._pose)

    def scan(self) -> np.ndarray:
        """Wall distances (n_beams,) in m along beams fixed to the robot, clipped at scan_max_range."""
        return self.sensor.scan(self._pose)

    # --- pickling ------------------------------------------------------------------------------------------
    def __getstate__(self) -> dict[str, Any]:
        return {
            "layout": self.layout,
            "robot": self.robot_params,
            "sensor": self.sensor_params,
            "odometry_noise": self.odometry_noise,
            "velocity_noise": self.velocity_noise,
            "wheel_noise": self.wheel_noise,
            "dt": self.dt,
            "substeps": self.substeps,
            "commands": np.array(self._commands, dtype=np.float64).reshape(-1, 2),
            "pose": self._pose,
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(
            state["layout"], state["robot"], state["sensor"], state["odometry_noise"],
            state["velocity_noise"], state["dt"], state["substeps"], wheel_noise=state.get("wheel_noise"),
        )  # fmt: skip
        for v, omega in state["commands"].tolist():
            self._commands.append((v, omega))
            self._advance(v, omega)
        if self._pose != tuple(state["pose"]):
            raise RuntimeError(
                f"replaying the pickled commands reached {self._pose}, not {tuple(state['pose'])}: "
                "was the world pickled with another pymunk version?"
            )
