"""The frontier planner acting in the macro action interfaces a policy learns in, so that it can teach one by
behaviour cloning and label the states a learner reaches (DAgger): a goal for the env's waypoint controller
(``FrontierWaypointPlanner``), or the motion primitive whose arc ends nearest that goal
(``FrontierPrimitivesPlanner``). Both follow the frontier agent's own path and mode state machine."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from ekfslam_gym.envs.actions import PRIMITIVES

from ..base import ActionKind, wall_scan
from ..navigation import arc_poses, arc_vetoed, scan_geometry
from .agent import FrontierAgent
from .geometry import in_robot_frame


class FrontierWaypointPlanner(FrontierAgent):
    """Nearest-frontier exploration acting in a ``waypoint`` env (``action.kind: waypoint``): once per env step
    it returns the goal the env's own waypoint controller drives to for up to ``action.hold`` control steps,
    the point of its path ``goal_distance`` m ahead in a free line of sight, relative to the estimated pose in
    units of ``action.waypoint_radius`` (the action space's Box(-1, 1, (2,))).

    This is the frontier agent's own mode of driving (a goal on the path for the waypoint controller) with the
    goal fixed for a macro step instead of moved at every control step, so it can teach a policy in the
    interface the policy acts in. Its step counters (stall, give-up and replanning timers) advance ``hold``
    control steps per env step, also when a macro step ended early (the controller reached its goal or a wall
    blocked it): in this interface the scarce resource is the episode's decisions, and a short macro step
    spends one as a full one does. ``goal_distance`` (m, at most the waypoint radius) should not be closer than
    the controller's slowing distance, which wastes the macro step. The settings' figures are in
    docs/research-log.md, *How the planners' defaults were chosen*.
    """

    name = "frontier-waypoint"
    action_kind = ActionKind.WAYPOINT

    def __init__(self, goal_distance: float = 1.5, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        if not goal_distance > 0:
            raise ValueError(f"goal_distance must be positive, got {goal_distance}")
        self.goal_distance = float(goal_distance)

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        cfg = self.env.config
        if cfg.action.kind != "waypoint":
            raise ValueError(
                f"the frontier-waypoint planner needs action.kind waypoint, got {cfg.action.kind}"
            )
        self._hold = int(cfg.action.steps)
        self._radius = float(cfg.action.waypoint_radius)
        self._reach = min(self.goal_distance, self._radius)
        self._acted = False  # no macro step driven yet

    def act(self, observation: Any) -> np.ndarray:
        pose = np.asarray(self.env.filter.pose, dtype=float)
        scan = wall_scan(self.env, observation)
        steps, self._acted = (self._hold if self._acted else 0), True
        if self._advance(pose, scan, steps) is None:  # nothing reachable to do: turn left in place
            return np.array([0.0, 0.1], dtype=np.float32)
        target = self._carrot_index(pose, self._reach)
        forward, left = in_robot_frame(pose, self._path[target])
        return np.clip(np.array([forward / self._radius, left / self._radius], dtype=np.float32), -1.0, 1.0)

    def __repr__(self) -> str:
        return f"FrontierWaypointPlanner(goal_distance={self.goal_distance})"


class FrontierPrimitivesPlanner(FrontierAgent):
    """Nearest-frontier exploration acting in a ``primitives`` env (``action.kind: primitives``): once per env
    step it returns the index (``np.int64``) of the primitive whose arc, held ``action.hold`` control steps
    from the estimated pose, ends nearest the point of its path ``goal_distance`` m ahead in a free line of
    sight, among the primitives the wall scan and the world's bounds do not rule out (the wall veto,
    ``ekfslam_gym.agents.navigation.arc_vetoed``, with ``clearance`` m beyond the robot's radius).

    It drives the frontier agent's path with the greedy planner's primitives, so that a Discrete policy can be
    taught nearest-frontier exploration in the interface the greedy clone acts in. Its step counters advance
    ``hold`` control steps per env step, as ``FrontierWaypointPlanner``'s do. A ``goal_distance`` shorter than
    an arc's reach makes the arcs overshoot the point. The settings' figures are in docs/research-log.md, *How
    the planners' defaults were chosen*.
    """

    name = "frontier-primitives"
    action_kind = ActionKind.PRIMITIVES

    def __init__(self, goal_distance: float = 1.5, clearance: float = 0.15, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        if not goal_distance > 0 or clearance < 0:
            raise ValueError(f"need goal_distance > 0 and clearance >= 0, got {goal_distance}, {clearance}")
        self.goal_distance = float(goal_distance)
        self.clearance = float(clearance)

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        u = self.env
        cfg = u.config
        if cfg.action.kind != "primitives" or u.action_space != gym.spaces.Discrete(len(PRIMITIVES)):
            raise ValueError(
                f"the frontier-primitives planner needs action.kind primitives, got {cfg.action.kind}"
            )
        self._hold = int(cfg.action.steps)
        self._arcs = [
            arc_poses(v * cfg.robot.v_max, w * cfg.robot.omega_max, cfg.dt, self._hold) for v, w in PRIMITIVES
        ]
        self._safe = cfg.robot.radius + self.clearance
        self._radius = cfg.robot.radius
        self._look_around = np.int64(PRIMITIVES.index((0.0, 1.0)))  # turning left in place
        self._acted = False  # no macro step driven yet

    def act(self, observation: Any) -> np.int64:
        pose = np.asarray(self.env.filter.pose, dtype=float)
        scan = wall_scan(self.env, observation)
        steps, self._acted = (self._hold if self._acted else 0), True
        if self._advance(pose, scan, steps) is None:  # nothing reachable to do
            return self._look_around
        forward, left = in_robot_frame(pose, self._path[self._carrot_index(pose, self.goal_distance)])
        points, segments = scan_geometry(scan, self._angles, self._scan_max)
        best, best_distance = self._look_around, math.inf  # a turn in place is never vetoed
        for index, arc in enumerate(self._arcs):
            distance = math.hypot(arc[-1, 0] - forward, arc[-1, 1] - left)
            if distance < best_distance and not arc_vetoed(
                arc, pose, points, segments, self._safe, self._bounds, self._radius
            ):
                best, best_distance = np.int64(index), distance
        return best

    def __repr__(self) -> str:
        return f"FrontierPrimitivesPlanner(goal_distance={self.goal_distance})"
