"""A differential-drive robot in a pymunk space: a dynamic disc steered through a kinematic control body.

Why a control body: setting a dynamic body's velocity each step overwrites what the contact solver decided, so
the robot drives through walls. Instead (as in pymunk's tank example) the command moves a kinematic control
body and a pivot joint and a gear joint, both with ``max_bias = 0`` (velocity constraints only, no position
correction), pull the robot's linear and angular velocity towards it with bounded force. The contact solver
sees those joints as finite forces, so a wall always wins. The bounds are just enough to reach any commanded
velocity within one substep, so in free space the robot tracks the command exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import pymunk

ROBOT_CATEGORY = 0b01
WALL_CATEGORY = 0b10
ROBOT_COLLISION_TYPE = 1
WALL_COLLISION_TYPE = 2


@dataclass(frozen=True)
class RobotParams:
    """The robot's body and limits.

    radius: m; mass: kg (a uniform disc). v_max: m/s and omega_max: rad/s, the command limits (commands are
    clipped to them). friction: Coulomb coefficient against walls (0 slides along them).
    """

    radius: float = 0.2
    mass: float = 1.0
    v_max: float = 1.0
    omega_max: float = 2.0
    friction: float = 0.0

    def __post_init__(self) -> None:
        for name in ("radius", "mass", "v_max", "omega_max"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"RobotParams.{name} must be finite and > 0, got {value!r}")
        if not (math.isfinite(self.friction) and self.friction >= 0.0):
            raise ValueError(f"RobotParams.friction must be finite and >= 0, got {self.friction!r}")


class DiffDriveRobot:
    """The robot's bodies, shape and joints, added to ``space`` at ``pose`` (x m, y m, theta rad).

    ``substep_dt`` (s) is the physics step the joint forces are sized for.
    """

    def __init__(
        self, space: pymunk.Space, pose: tuple[float, float, float], params: RobotParams, substep_dt: float
    ) -> None:
        self.params = params
        moment = pymunk.moment_for_circle(params.mass, 0.0, params.radius)
        self.control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        self.control.position = (pose[0], pose[1])
        self.control.angle = pose[2]
        self.body = pymunk.Body(params.mass, moment)
        self.body.position = (pose[0], pose[1])
        self.body.angle = pose[2]
        self.shape = pymunk.Circle(self.body, params.radius)
        self.shape.friction = params.friction
        self.shape.elasticity = 0.0
        self.shape.collision_type = ROBOT_COLLISION_TYPE
        self.shape.filter = pymunk.ShapeFilter(categories=ROBOT_CATEGORY)

        pivot = pymunk.PivotJoint(self.control, self.body, (0.0, 0.0), (0.0, 0.0))
        pivot.max_bias = 0.0
        pivot.max_force = params.mass * 2.0 * params.v_max / substep_dt
        gear = pymunk.GearJoint(self.control, self.body, 0.0, 1.0)
        gear.max_bias = 0.0
        gear.max_force = moment * 2.0 * params.omega_max / substep_dt
        space.add(self.control, self.body, self.shape, pivot, gear)
        self._chipmunk = _chipmunk_calls(space, self.control, self.body)

    def advance(
        self,
        space: pymunk.Space,
        v: float,
        omega: float,
        substep_dt: float,
        substeps: int,
        trace: list[tuple[float, float, float]] | None = None,
    ) -> None:
        """Step ``space`` ``substeps`` times of ``substep_dt`` s, commanding forward speed v (m/s) and turn
        rate omega (rad/s); append the pose after each substep to ``trace`` if one is given.

        pymunk integrates positions *before* it solves velocities, so the velocity solved in one substep moves
        the body in the next: the robot answers a new command one substep late (a small, physical latency).
        The commanded velocity therefore points along the heading at the middle of that next substep, so
        in free space each substep's motion is exactly the chord of an arc (a step whose command changed is
        two different arcs, not one: what wheel odometry integrated at the substep rate sees).
        """
        if self._chipmunk is not None and self._chipmunk[0] is space:
            (
                _,
                step,
                handle,
                get_angle,
                get_angular_velocity,
                set_velocity,
                set_angular_velocity,
                c,
                b,
                position,
            ) = self._chipmunk
            set_angular_velocity(c, omega)
            for _ in range(substeps):
                heading = get_angle(b) + (get_angular_velocity(b) + 0.5 * omega) * substep_dt
                set_velocity(c, (v * math.cos(heading), v * math.sin(heading)))
                step(handle, substep_dt)
                if trace is not None:
                    p = position(b)
                    trace.append((p.x, p.y, get_angle(b)))
            return
        control = self.control
        body = self.body
        control.angular_velocity = omega
        for _ in range(substeps):
            # heading now, plus this substep's turn at the current rate, plus half the next substep's turn
            heading = body.angle + (body.angular_velocity + 0.5 * omega) * substep_dt
            control.velocity = (v * math.cos(heading), v * math.sin(heading))
            space.step(substep_dt)
            if trace is not None:
                p = body.position
                trace.append((p.x, p.y, body.angle))

    def pose(self) -> tuple[float, float, float]:
        """True pose (x m, y m, theta rad), theta unwrapped (continuous over the episode)."""
        calls = self._chipmunk
        if calls is not None:  # the same C getters pymunk's properties call, without building a Vec2d
            b = calls[8]
            p = calls[9](b)
            return (p.x, p.y, calls[3](b))
        p = self.body.position
        return (p.x, p.y, self.body.angle)


def _chipmunk_calls(space: pymunk.Space, control: pymunk.Body, body: pymunk.Body) -> tuple | None:
    """Chipmunk's own functions and the C handles of ``space`` and the two bodies, or None where this pymunk
    does not expose them (``advance`` then goes through pymunk's Python API).

    Why: pymunk's Python layer costs ~1.7 us per substep here (an attribute hook on every property set, and
    bookkeeping in ``Space.step`` for bodies added or removed during a step, which the robot never does),
    about 6 % of an env step. The direct calls are the same C functions in the same order;
    ``tests/sim/test_world.py`` holds them to the Python API's poses and contacts exactly.
    """
    try:
        from pymunk._chipmunk import lib

        return (
            space, lib.cpSpaceStep, space._space, lib.cpBodyGetAngle, lib.cpBodyGetAngularVelocity,
            lib.cpBodySetVelocity, lib.cpBodySetAngularVelocity, control._body, body._body, lib.cpBodyGetPosition,
        )  # fmt: skip
    except (ImportError, AttributeError):
        return None
