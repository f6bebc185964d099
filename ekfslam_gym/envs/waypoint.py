"""A waypoint controller: drive to a goal with only what the robot has, its pose estimate and its wall scan.

The controller maps (pose estimate, goal, wall scan) to a normalised action (v / v_max, omega / omega_max) in
[-1, 1]^2; it holds no state, so the same inputs always give the same action. It neither knows the walls'
geometry nor the true pose: an agent (or a ``waypoint`` action interface) gives it a goal and calls it at
every control step until it reports ``reached`` or ``blocked``.

Steering is the proportional heading law of a differential-drive robot (Thrun, Burgard & Fox, *Probabilistic
Robotics*, ch. 5, the velocity motion model): turn at ``heading_gain`` times the heading error, drive forward
at a speed that fades to zero as the error grows to ``turn_in_place`` (so large errors are turned in place,
and the robot never circles its goal) and that slows within ``slow_distance`` of the goal.

Safety comes from the scan alone (the reactive layer of the *Robot Mapping* course's navigation stack): the
beam end points that hit a wall, and the segments joining neighbouring end points closer than ``join`` m
(one surface seen by two beams), are obstacles. ``travel_distance`` gives how far the robot's disc, inflated
by ``margin``, can move straight ahead before touching one; the forward speed is capped so that the robot
stops ``clearance`` m short of that contact, slowing over the last ``braking`` m. Blocked with the goal ahead
(a wall between them), it turns in place away from the wall; with an obstacle already closer than its inflated
radius in front, it backs off if the space behind is free. Turning in place never hits anything: the robot is
a disc.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from .. import compiled


class Command(NamedTuple):
    """One control step: the normalised action and the controller's verdict on the goal.

    v, omega: forward speed / v_max and turn rate / omega_max, in [-1, 1]. reached: the pose estimate is
    within ``tolerance`` m of the goal (the action is then zero). blocked: a wall in the scan stops the robot
    short of a goal that lies ahead of it.
    """

    v: float
    omega: float
    reached: bool
    blocked: bool

    def action(self) -> np.ndarray:
        """The action as the env takes it: float32 (2,)."""
        return np.array([self.v, self.omega], dtype=np.float32)


def goal_in_world(pose: Any, forward: float, left: float) -> tuple[float, float]:
    """The world point ``forward`` m ahead and ``left`` m to the left of ``pose`` (x, y, theta): how a goal given
    relative to the *estimated* pose becomes a fixed world goal for the controller."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return pose[0] + c * forward - s * left, pose[1] + s * forward + c * left


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def travel_distance(xs: Any, ys: Any, hit: Any, rho: float, join: float) -> float:
    """How far (m) a disc of radius ``rho`` at the origin can move along +x before it touches a wall.

    ``xs``, ``ys``: the scan's end points in a frame whose x axis is the direction of travel, beam by beam
    around the circle; ``hit``: which beams ended on a wall. The walls are the hit end points and the segments
    joining neighbouring hit end points less than ``join`` m apart. 0 when a wall in front already overlaps
    the disc; inf when nothing lies in the way. (The compiled ``clearance_kernels.travel_distance``.)
    """
    xs = np.ascontiguousarray(xs, dtype=np.float64).reshape(-1)
    ys = np.ascontiguousarray(ys, dtype=np.float64).reshape(-1)
    hit = np.ascontiguousarray(hit, dtype=np.bool_).reshape(-1)
    if not xs.shape == ys.shape == hit.shape:
        raise ValueError(
            f"xs, ys and hit must have one entry per beam, got {xs.shape}, {ys.shape}, {hit.shape}"
        )
    return float(compiled.travel_distance(xs, ys, hit, float(rho), float(join)))


class WaypointController:
    """Drive to a world goal from the pose estimate and the wall scan; stateless and deterministic.

    Args:
        v_max, omega_max: the robot's limits (m/s, rad/s), the action's scale. radius: the robot's (m).
        n_beams: scan beams, beam i at heading + 2 pi i / n_beams. scan_max_range: m, where a beam saw nothing.
        dt: the control period (s). tolerance: m from the goal that counts as reached. clearance: m kept
            between the (inflated) robot and a scanned wall ahead. margin: m added to the radius for the
            contact test (the scan's beams are 2 pi / n_beams apart, so a wall's nearest point may fall
            between them). braking: m over which the speed is cut to zero before the clearance (default 3
            control steps at full speed). heading_gain: turn rate per radian of heading error (1/s).
            turn_in_place: heading error (rad) at and beyond which the robot only turns. slow_distance: m from
            the goal within which the speed shrinks in proportion. backoff: speed (fraction of v_max) of
            backing off a wall closer than the inflated radius. join: m, end points closer than this are one
            surface. min_speed: speed (fraction of v_max) below which a wall-capped robot counts as blocked (the
            cap shrinks geometrically as it closes in).
    """

    def __init__(
        self,
        v_max: float,
        omega_max: float,
        radius: float,
        n_beams: int,
        scan_max_range: float,
        dt: float,
        *,
        tolerance: float = 0.3,
        clearance: float = 0.15,
        margin: float = 0.05,
        braking: float | None = None,
        heading_gain: float = 3.0,
        turn_in_place: float = math.pi / 3.0,
        slow_distance: float = 0.6,
        backoff: float = 0.3,
        join: float = 1.5,
        min_speed: float = 0.05,
    ) -> None:
        for name, value in (("v_max", v_max), ("omega_max", omega_max), ("radius", radius), ("dt", dt),
                            ("scan_max_range", scan_max_range), ("tolerance", tolerance),
                            ("heading_gain", heading_gain), ("turn_in_place", turn_in_place),
                            ("slow_distance", slow_distance)):  # fmt: skip
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be finite and > 0, got {value!r}")
        for name, value in (("clearance", clearance), ("margin", margin), ("backoff", backoff), ("join", join),
                            ("min_speed", min_speed)):  # fmt: skip
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
        if isinstance(n_beams, bool) or not isinstance(n_beams, int) or n_beams < 1:
            raise ValueError(f"n_beams must be an int >= 1, got {n_beams!r}")
        self.v_max = float(v_max)
        self.omega_max = float(omega_max)
        self.radius = float(radius)
        self.n_beams = n_beams
        self.scan_max_range = float(scan_max_range)
        self.dt = float(dt)
        self.tolerance = float(tolerance)
        self.clearance = float(clearance)
        self.margin = float(margin)
        self.braking = float(braking) if braking is not None else 3.0 * v_max * dt
        if not (math.isfinite(self.braking) and self.braking > 0.0):
            raise ValueError(f"braking must be finite and > 0, got {braking!r}")
        self.heading_gain = float(heading_gain)
        self.turn_in_place = float(turn_in_place)
        self.slow_distance = float(slow_distance)
        self.backoff = min(float(backoff), 1.0)
        self.join = float(join)
        self.min_speed = float(min_speed)
        angles = [2.0 * math.pi * i / n_beams for i in range(n_beams)]
        self._beam_cos = np.array([math.cos(a) for a in angles])
        self._beam_sin = np.array([math.sin(a) for a in angles])
        self._sin = self._beam_sin.tolist()
        self._rho = self.radius + self.margin

    @classmethod
    def from_config(cls, config: Any, **kwargs: Any) -> WaypointController:
        """The controller for an env's config (its ``robot``, ``sensor`` and ``dt``), with ``kwargs`` on top."""
        robot, sensor = config.robot, config.sensor
        return cls(
            robot.v_max,
            robot.omega_max,
            robot.radius,
            sensor.n_beams,
            sensor.scan_max_range,
            config.dt,
            **kwargs,
        )

    def clearances(self, scan: Any) -> tuple[float, float]:
        """How far (m) the inflated robot can drive straight ahead and straight back before touching a wall
        the scan shows (inf when nothing is in the way)."""
        ahead, behind, _ = self._clearances(scan)
        return ahead, behind

    def clearance_ahead(self, scan: Any) -> float:
        """``clearances(scan)[0]`` alone (half the work): the room ahead, for the primitives' guard."""
        return self._clearances(scan, False)[0]

    def _clearances(self, scan: Any, behind_too: bool = True) -> tuple[float, float, float]:
        """(room ahead, room behind, nearest hit range), m: ``clearance_kernels.scan_clearances``."""
        ranges = np.ascontiguousarray(scan, dtype=np.float64)
        if ranges.shape != (self.n_beams,):
            raise ValueError(f"scan must have {self.n_beams} beams, got shape {ranges.shape}")
        limit = self.scan_max_range - 1e-6
        cos, sin = self._beam_cos, self._beam_sin
        return compiled.scan_clearances(ranges, cos, sin, limit, self._rho, self.join, behind_too)

    def command(self, pose: Any, goal: Any, scan: Any) -> Command:
        """The action towards ``goal`` (x, y in the world, m) from the pose estimate ``pose`` (x, y, theta)
        given the wall scan ``scan`` (m per beam, ``scan_max_range`` where nothing was hit)."""
        x, y, theta = float(pose[0]), float(pose[1]), float(pose[2])
        dx, dy = float(goal[0]) - x, float(goal[1]) - y
        if not all(map(math.isfinite, (x, y, theta, dx, dy))):
            raise ValueError(f"pose and goal must be finite, got {pose!r}, {goal!r}")
        distance = math.hypot(dx, dy)
        if distance <= self.tolerance:
            return Command(0.0, 0.0, True, False)
        error = _wrap(math.atan2(dy, dx) - theta)
        omega = max(-1.0, min(1.0, self.heading_gain * error / self.omega_max))
        alignment = max(0.0, 1.0 - abs(error) / self.turn_in_place)
        v = alignment * min(1.0, distance / self.slow_distance)
        if v <= 0.0:
            return Command(0.0, omega, False, False)  # turning in place is always safe: the robot is a disc

        ahead = self.clearance_ahead(scan)  # the room behind is needed only when blocked, below
        room = ahead - self.clearance
        cap = max(0.0, room) / self.braking
        if cap >= min(v, self.min_speed):
            return Command(min(v, cap), omega, False, False)
        # Blocked with the goal ahead: back off if a wall already overlaps the inflated robot in front, and
        # turn in place away from the wall (towards the side with more room) so the robot can get round it.
        _, behind, nearest = self._clearances(scan)
        if ahead <= 0.0 and nearest < self._rho and behind > self.clearance:
            v = -self.backoff * min(1.0, (behind - self.clearance) / self.braking)
        else:
            v = 0.0
        return Command(v, self._turn_away(scan, error), False, True)

    def _turn_away(self, scan: Any, error: float) -> float:
        """Full turn rate towards the half of the scan with more room, ties towards the goal's side."""
        ranges = scan.tolist() if hasattr(scan, "tolist") else list(scan)
        left = right = 0.0
        for r, s in zip(ranges, self._sin):
            if s > 1e-9:
                left += r
            elif s < -1e-9:
                right += r
        if left == right:
            return 1.0 if error >= 0.0 else -1.0
        return 1.0 if left > right else -1.0
