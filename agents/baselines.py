"""The simple baselines: uniform random actions, a fixed circle, and a lawnmower (boustrophedon) sweep."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from ekfslam_gym.angles import wrap_angle

from .base import Agent, beam_angles, clip_action, wall_scan


class RandomAgent(Agent):
    """Uniform random actions in [-1, 1]^2 from the agent's own seeded generator: the floor of the table."""

    name = "random"

    def act(self, observation: Any) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, size=2).astype(np.float32)


class CircleAgent(Agent):
    """Drive a fixed circle of ``radius`` m at ``speed`` (fraction of v_max), turning left: a sanity floor.

    Blind: it uses neither the belief nor the scan, so where the circle meets a wall it slides along it. The
    default radius is the one with the highest return (information gain less the collision penalty) in
    EKFSLAM-v0, from a sweep over 0.5-8 m at full speed (training seeds 0-19, then 6-7.5 m on seeds 0-39):
    the information grows with the radius (more of the arena passes through the field of view) up to about
    7 m, where sliding along the walls starts to cost more than it finds. At 6.5 m the robot touches a wall
    in about a fifth of the steps.
    """

    name = "circle"

    def __init__(self, radius: float = 6.5, speed: float = 1.0) -> None:
        super().__init__()
        if not (radius > 0 and 0 < speed <= 1):
            raise ValueError(f"need radius > 0 m and speed in (0, 1], got {radius!r}, {speed!r}")
        self.radius = float(radius)
        self.speed = float(speed)
        self._action = clip_action(speed, 0.0)

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        robot = self.env.config.robot
        omega = self.speed * robot.v_max / self.radius  # rad/s
        self._action = clip_action(self.speed, omega / robot.omega_max)

    def act(self, observation: Any) -> np.ndarray:
        return self._action.copy()

    def __repr__(self) -> str:
        return f"CircleAgent(radius={self.radius}, speed={self.speed})"


class LawnmowerAgent(Agent):
    """A boustrophedon coverage sweep of the world's bounds, steered by the pose *estimate*.

    What it knows: the world's bounds (the rectangle the observation's coverage grid spans), the sensor's
    range, its own pose estimate (the filter's mean) and the observation's wall scan. Not the walls' geometry
    nor the landmarks. Lanes run along the longer side, ``lane_spacing`` m apart (evenly spread between the
    bounds, half a spacing in from each side) and stop ``end_margin`` m short of the bounds (the sensor
    looks ahead, so driving into the corners adds little), from the corner nearest the start; when the sweep is
    done it
    sweeps again across the other axis, which revisits the landmarks from new directions (loop closures).

    Steering: pure pursuit to the next lane end, slowing to turn in place for large heading errors. When the
    scan shows a wall closer than ``avoid_distance`` m ahead it turns in place towards the more open side and
    then drives straight for ``escape_steps`` steps; a waypoint it cannot reach within ``give_up_steps``
    steps is skipped (rooms and loops put walls across lanes).
    """

    name = "lawnmower"

    def __init__(
        self,
        lane_spacing: float | None = None,
        end_margin: float | None = None,
        tolerance: float = 0.5,
        avoid_distance: float = 0.7,
        give_up_steps: int = 60,
        escape_steps: int = 15,
    ) -> None:
        super().__init__()
        self.lane_spacing = lane_spacing
        self.end_margin = end_margin
        self.tolerance = tolerance
        self.avoid_distance = avoid_distance
        self.give_up_steps = give_up_steps
        self.escape_steps = escape_steps
        self._escape = 0
        self._escape_turn = 1.0
        self._waypoints = np.zeros((0, 2))
        self._index = 0
        self._pass = 0
        self._steps_on_waypoint = 0

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        cfg = self.env.config
        self._bounds = np.asarray(self.env.world.layout.bounds, dtype=float)  # the world's extent only
        self._angles = beam_angles(cfg.sensor.n_beams)
        # Defaults in sensor ranges, the best of a sweep in EKFSLAM-v0 (spacing 5-14 m, end margin 0.5-5 m,
        # training seeds 0-39): lanes 8 m apart stopping 4 m from the walls; with a half-plane field of view a
        # lane sees most of a range to each side, and the flat optimum (5-8 m within 1 %) favours fewer turns.
        range_ = cfg.sensor.max_range
        self._spacing = float(self.lane_spacing if self.lane_spacing is not None else 4.0 / 3.0 * range_)
        self._end_margin = float(self.end_margin if self.end_margin is not None else 2.0 / 3.0 * range_)
        self._pass = 0
        pose = np.asarray(self.env.filter.pose, dtype=float)
        self._waypoints = self._sweep(pose[:2], along_x=self._longer_axis_is_x())
        self._index = 0
        self._steps_on_waypoint = 0
        self._escape = 0

    @property
    def waypoints(self) -> np.ndarray:
        """The current sweep's lane end points (k, 2), m, in visiting order."""
        return self._waypoints.copy()

    def _longer_axis_is_x(self) -> bool:
        b = self._bounds
        return (b[2] - b[0]) >= (b[3] - b[1])

    def _sweep(self, start_xy: np.ndarray, along_x: bool) -> np.ndarray:
        """Lane end points in visiting order, starting from the corner of the sweep nearest ``start_xy``."""
        xmin, ymin, xmax, ymax = self._bounds
        if not along_x:  # work in swapped coordinates, swap back at the end
            xmin, ymin, xmax, ymax = ymin, xmin, ymax, xmax
            start_xy = start_xy[::-1]
        across = ymax - ymin
        edge = min(0.5 * self._spacing, 0.5 * across)
        n_lanes = max(1, int(round((across - 2.0 * edge) / self._spacing)) + 1)
        lanes = (
            np.linspace(ymin + edge, ymax - edge, n_lanes) if n_lanes > 1 else np.array([0.5 * (ymin + ymax)])
        )
        margin = min(self._end_margin, 0.45 * (xmax - xmin))
        ends = np.array([xmin + margin, xmax - margin])
        if abs(start_xy[1] - lanes[-1]) < abs(start_xy[1] - lanes[0]):
            lanes = lanes[::-1]
        if abs(start_xy[0] - ends[1]) < abs(start_xy[0] - ends[0]):
            ends = ends[::-1]
        points = []
        for i, y in enumerate(lanes):
            a, b = (ends[0], ends[1]) if i % 2 == 0 else (ends[1], ends[0])
            points += [(a, y), (b, y)]
        out = np.array(points, dtype=float)
        return out if along_x else out[:, ::-1].copy()

    def act(self, observation: Any) -> np.ndarray:
        pose = np.asarray(self.env.filter.pose, dtype=float)
        scan = wall_scan(self.env, observation)
        for _ in range(2 * len(self._waypoints) + 2):  # skip reached waypoints; bounded, whatever the sweep
            if self._index >= len(self._waypoints):
                self._pass += 1
                along_x = self._longer_axis_is_x() ^ (self._pass % 2 == 1)
                self._waypoints = self._sweep(pose[:2], along_x)
                self._index = 0
            offset = self._waypoints[self._index] - pose[:2]
            if float(np.hypot(*offset)) >= self.tolerance and self._steps_on_waypoint <= self.give_up_steps:
                break
            self._index += 1
            self._steps_on_waypoint = 0
        self._steps_on_waypoint += 1

        error = wrap_angle(math.atan2(offset[1], offset[0]) - pose[2])
        bearings = np.array([wrap_angle(a) for a in self._angles])
        ahead = np.abs(bearings) <= math.radians(30.0)
        if scan[ahead].min() < self.avoid_distance:
            # Blocked: turn in place towards the half with more room (its summed clearances), then drive
            # clear for a while before steering for the waypoint again, or it would turn straight back.
            if self._escape <= 0:
                left = scan[(bearings > 0) & (bearings < math.pi)].sum()
                right = scan[(bearings < 0) & (bearings > -math.pi)].sum()
                self._escape_turn = 1.0 if left >= right else -1.0
            self._escape = self.escape_steps
            return clip_action(0.0, self._escape_turn)
        if self._escape > 0:
            self._escape -= 1
            return clip_action(1.0, 0.0)
        omega_max = self.env.config.robot.omega_max
        turn = 2.0 * error / omega_max  # proportional heading control, gain 2 /s
        speed = max(0.0, math.cos(error)) ** 3 if abs(error) < 0.5 * math.pi else 0.0
        return clip_action(speed, turn)

    def __repr__(self) -> str:
        return f"LawnmowerAgent(lane_spacing={self.lane_spacing})"
