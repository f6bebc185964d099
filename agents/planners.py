"""The planners that demonstrate in a macro action interface, for behaviour cloning (``ekfslam_gym.training``).

A policy learns faster when a planner teaches it first (imitation, then RL: planner-guided training).
For the demonstrations to be imitable they must be in the policy's own interface. Two planners act in one:

- ``greedy``: ``GreedyPrimitivesPlanner``, the greedy information-gain planner (``ekfslam_gym.agents.greedy``)
  choosing, once per env step of a primitives env (``action.kind: primitives``), the index of the primitive to
  hold for ``action.hold`` control steps, planned from the env's belief exactly as the velocity agent plans;
- ``frontier``: nearest-frontier exploration in either interface: ``frontier.FrontierWaypointPlanner`` giving,
  once per env step of a waypoint env (``action.kind: waypoint``), the goal on its path for the env's waypoint
  controller; ``frontier.FrontierPrimitivesPlanner`` choosing, in a primitives env, the primitive whose arc ends
  nearest that goal.

``make_planner(name, kind)`` builds one for an action interface. Each planner class declares the interface it
acts in (``action_kind``), and ``PLANNERS`` is read from those declarations.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from ekfslam_gym.envs.actions import PRIMITIVES

from .base import ActionKind, Agent, wall_scan
from .frontier import FrontierPrimitivesPlanner, FrontierWaypointPlanner
from .greedy import GreedyInfoGainAgent, primitive_controls
from .navigation import WALL_JOIN, mark_seen, scan_geometry, to_world, update_walls


class GreedyPrimitivesPlanner(GreedyInfoGainAgent):
    """The greedy planner acting in a primitives env: ``act`` returns the index (``np.int64``) of the primitive
    it chooses, replanning every env step (one env step holds a primitive for ``action.hold`` >= the velocity
    agent's ``replan_every`` control steps).

    The velocity agent marks its coverage grid at every control step; here the control steps inside a macro
    step are not observed, so the grid is marked at the poses the executed primitive predicts from the estimate
    at the step's start (the planner's own rollout arc, the belief's dead reckoning), then at the new estimate
    with the new wall scan. When every primitive is vetoed it turns in place towards the more open side, as the
    velocity agent does.
    """

    name = "greedy-primitives"
    action_kind = ActionKind.PRIMITIVES

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        u = self.env
        if u.config.action.kind != "primitives" or u.action_space != gym.spaces.Discrete(len(PRIMITIVES)):
            raise ValueError(
                f"the greedy-primitives planner needs an env with action.kind primitives, got {u.config.action.kind}"
            )
        if not np.array_equal(self.primitives, np.asarray(PRIMITIVES, dtype=float)):
            raise ValueError("the planner's primitives must be the env's PRIMITIVES (an index names one)")
        cfg = u.config
        self._hold = int(cfg.action.hold)
        # The arcs each primitive drives over one macro step, relative to its start (for marking the grid).
        self._arcs = [
            primitive_controls(v * cfg.robot.v_max, w * cfg.robot.omega_max, cfg.dt, self._hold,
                               u.filter.motion_model, self._motion_noise)[2]
            for v, w in self.primitives
        ]  # fmt: skip
        self._turn = {
            side: PRIMITIVES.index((0.0, side)) for side in (1.0, -1.0)
        }  # the turns in place, the way out when everything is vetoed
        self._executed: int | None = None
        self._start: np.ndarray | None = None

    def act(self, observation: Any) -> np.int64:
        pose = np.asarray(self.env.filter.pose, dtype=float)
        scan = wall_scan(self.env, observation)
        b = self._bounds
        half_fov = 0.5 * self._fov
        if self._executed is not None:
            for x, y, theta in to_world(self._arcs[self._executed][1:-1], self._start):
                mark_seen(self._seen, self._hidden, self._wall, b[0], b[1], self.cell, x, y, theta,
                          self._max_range, half_fov)  # fmt: skip
        update_walls(
            self._wall, b[0], b[1], self.cell, pose[0], pose[1], pose[2], self._angles, scan,
            self._scan_max - 1e-6, WALL_JOIN,
        )  # fmt: skip
        mark_seen(self._seen, self._hidden, self._wall, b[0], b[1], self.cell, pose[0], pose[1], pose[2],
                  self._max_range, half_fov)  # fmt: skip
        points, segments = scan_geometry(scan, self._angles, self._scan_max)
        self._current = self._plan(pose, points, segments)
        if self._current >= 0:
            index = self._current
        else:
            left = scan[(self._angles > 0) & (self._angles < math.pi)].sum()
            right = scan[self._angles > math.pi].sum()
            index = self._turn[1.0 if left >= right else -1.0]
        self._executed, self._start = index, pose
        return np.int64(index)

    def executed(self, index: int) -> None:
        """Note that primitive ``index`` was executed instead of the planner's choice (a learner drove, the
        planner only labels: DAgger), so the coverage grid is marked along the path actually driven and the
        commitment bonus goes to the primitive being executed."""
        if int(index) != self._executed:
            self._executed = self._current = int(index)

    def __repr__(self) -> str:
        return f"GreedyPrimitivesPlanner(horizon={self.horizon})"


# The demonstration planners by name, each a class per action interface it acts in.
PLANNER_CLASSES: dict[str, tuple[type[Agent], ...]] = {
    "greedy": (GreedyPrimitivesPlanner,),
    "frontier": (FrontierWaypointPlanner, FrontierPrimitivesPlanner),
}
# The interfaces (``action.kind``) each planner acts in, from the classes' declarations.
PLANNERS: dict[str, tuple[str, ...]] = {
    name: tuple(str(cls.action_kind) for cls in classes) for name, classes in PLANNER_CLASSES.items()
}


def make_planner(name: str, kind: str, **kwargs: Any) -> Agent:
    """The demonstration planner ``name`` (a key of ``PLANNERS``) for action interface ``kind`` (an
    ``action.kind``), built with ``kwargs``; ValueError when the planner does not act in that interface."""
    if name not in PLANNERS:
        raise ValueError(f"unknown demonstration planner {name!r}; choose one of {list(PLANNERS)}")
    for cls in PLANNER_CLASSES[name]:
        if cls.action_kind == kind:
            return cls(**kwargs)
    raise ValueError(
        f"the {name} planner demonstrates in action.kind {' or '.join(PLANNERS[name])}, not {str(kind)!r}"
    )
