"""Team baselines: random robots, independent nearest-frontier robots, and coordinated frontier assignment.

A team agent is reset with the team env (``reset(team, seed)``) and maps every live robot's observation to its
action (``act(observations) -> {agent: action}``); nothing here steps the env.

- ``RandomTeam``: each robot a uniform random primitive.
- ``IndependentFrontierTeam``: each robot runs the single-robot nearest-frontier planner
  (``ekfslam_gym.agents.frontier.FrontierPrimitivesPlanner``, Yamauchi 1997) on the team's shared coverage
  memory and the joint belief, unaware of its teammates' goals: robots near each other chase the same frontier.
- ``CoordinatedFrontierTeam``: Burgard, Moors, Stachniss & Schneider, "Coordinated multi-robot exploration"
  (IEEE T-RO 21(3), 2005): every frontier cell starts with utility 1; robots are given targets one at a time,
  each time the (robot, frontier) pair of largest utility minus ``beta`` times the robot's path cost to it,
  and the utility of every frontier cell within the sensor's range of the chosen one drops by
  1 - distance / range, so the next robot prefers frontiers out of sight of those already taken, which keeps
  the robots apart. Each robot then drives to its target as the single-robot planner drives to its frontier.

Both frontier teams read only the belief (the joint filter's estimates, the shared coverage memory, each
robot's own wall scan), through ``RobotView``: one robot's view of the team env, shaped as the single-robot
env the planners are written for.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from ..agents.base import wall_scan
from ..agents.frontier import (
    FrontierPrimitivesPlanner,
    frontier_cells,
    frontier_regions,
    grid_paths,
    path_sources,
)
from .env import TeamSLAMEnv


class RobotFilterView:
    """Robot ``robot``'s view of the team filter, with ``EKFSLAM``'s attribute names (``pose`` and
    ``pose_cov`` that robot's; the map the team's)."""

    def __init__(self, team_filter: Any, robot: int) -> None:
        self._filter = team_filter
        self._robot = robot

    @property
    def n_landmarks(self) -> int:
        return self._filter.n_landmarks

    @property
    def pose(self) -> np.ndarray:
        return self._filter.pose(self._robot)

    @property
    def pose_cov(self) -> np.ndarray:
        return self._filter.pose_cov(self._robot)

    @property
    def landmarks(self) -> np.ndarray:
        return self._filter.landmarks

    @property
    def observed(self) -> np.ndarray:
        return self._filter.observed

    def landmark_covs(self) -> np.ndarray:
        return self._filter.landmark_covs()


class RobotView:
    """One robot's view of the team env, shaped as the single-robot env (``config``, ``filter``,
    ``coverage_memory``, ``bounds``, ``observation_layout``, ``action_space``), for the single-robot planners."""

    def __init__(self, team: TeamSLAMEnv, robot: int) -> None:
        self.team = team
        self.robot = robot
        self.config = team.config
        self.action_space = team.action_space(team.possible_agents[robot])
        self.filter = RobotFilterView(team.filter, robot)

    @property
    def unwrapped(self) -> RobotView:
        return self

    @property
    def coverage_memory(self) -> np.ndarray:
        return self.team.coverage_memory

    @property
    def bounds(self) -> np.ndarray:
        return self.team.bounds

    @property
    def observation_layout(self):
        return self.team.observation_layout


class TeamAgent:
    """Base class: ``reset(team, seed)`` once per episode, then ``act(observations) -> {agent: action}``."""

    name = "team-agent"

    def reset(self, team: TeamSLAMEnv, seed: int | None = None) -> None:
        self.team = team
        self.rng = np.random.default_rng(seed)

    def act(self, observations: Mapping[str, np.ndarray]) -> dict[str, Any]:
        raise NotImplementedError


class RandomTeam(TeamAgent):
    """Every robot a uniform random motion primitive."""

    name = "random"

    def act(self, observations: Mapping[str, np.ndarray]) -> dict[str, int]:
        n = self.team.action_space(self.team.possible_agents[0]).n
        return {agent: int(self.rng.integers(n)) for agent in observations}


class IndependentFrontierTeam(TeamAgent):
    """Every robot the single-robot nearest-frontier planner, on the shared map, unaware of the others' goals."""

    name = "frontier-independent"

    def __init__(self, **planner_kwargs: Any) -> None:
        self.planner_kwargs = planner_kwargs

    def _planner(self) -> FrontierPrimitivesPlanner:
        return FrontierPrimitivesPlanner(**self.planner_kwargs)

    def reset(self, team: TeamSLAMEnv, seed: int | None = None) -> None:
        super().reset(team, seed)
        self.planners = []
        for i in range(team.n_robots):
            planner = self._planner()
            planner.reset(RobotView(team, i), None if seed is None else seed + i)
            self.planners.append(planner)

    def act(self, observations: Mapping[str, np.ndarray]) -> dict[str, int]:
        agents = self.team.possible_agents
        return {
            agent: int(self.planners[agents.index(agent)].act(obs)) for agent, obs in observations.items()
        }


class AssignedFrontierPlanner(FrontierPrimitivesPlanner):
    """The frontier-primitives planner driving to the frontier cell its coordinator assigned (``assigned``,
    (row, col) or None: then its own nearest frontier), replanning when the assignment changes."""

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        self.assigned: tuple[int, int] | None = None

    def frontiers(self) -> np.ndarray:
        own = super().frontiers()
        if self.assigned is None or not own[self.assigned]:
            return own
        mask = np.zeros_like(own)
        mask[self.assigned] = True
        return mask

    def _needs_plan(self, pose: np.ndarray) -> bool:
        if self.assigned is not None and self._goal != self.assigned:
            return True
        return super()._needs_plan(pose)


def utility_cost_assignment(costs: np.ndarray, targets: np.ndarray, beta: float, reach: float) -> list[int]:
    """Burgard et al. (2005)'s greedy assignment: ``costs`` (robots, targets) the path costs (m, inf where
    unreachable), ``targets`` (k, 2) their positions (m). Every target starts with utility 1; while a robot is
    left, the (robot, target) pair of largest utility - ``beta`` cost is chosen, and every target within
    ``reach`` m of the chosen one loses 1 - distance / reach of its utility. Returns each robot's target index
    (-1: none reachable)."""
    n = costs.shape[0]
    utility = np.ones(costs.shape[1])
    chosen = [-1] * n
    free = list(range(n))
    while free and costs.shape[1]:
        value = utility[None, :] - beta * costs[free]
        best = np.unravel_index(int(np.argmax(value)), value.shape)
        if not np.isfinite(value[best]):
            break
        robot, t = free[best[0]], int(best[1])
        chosen[robot] = t
        free.remove(robot)
        d = np.hypot(targets[:, 0] - targets[t, 0], targets[:, 1] - targets[t, 1])
        utility -= np.where(d < reach, 1.0 - d / reach, 0.0)
    return chosen


class CoordinatedFrontierTeam(IndependentFrontierTeam):
    """Burgard et al. (2005)'s coordinated frontier assignment (the module docstring).

    ``beta``: utility per metre of path (the cost's weight; path cost plus the planner's ``turn_cost`` m per
    radian of turning to face the target). ``reach``: m, the range within which a taken frontier discounts
    others (default the sensor's ``max_range``).
    """

    name = "frontier-coordinated"

    def __init__(self, beta: float = 0.05, reach: float | None = None, **planner_kwargs: Any) -> None:
        super().__init__(**planner_kwargs)
        if not beta > 0 or (reach is not None and not reach > 0):
            raise ValueError(f"need beta > 0 and reach > 0, got {beta}, {reach}")
        self.beta = float(beta)
        self.reach = reach

    def _planner(self) -> AssignedFrontierPlanner:
        return AssignedFrontierPlanner(**self.planner_kwargs)

    def reset(self, team: TeamSLAMEnv, seed: int | None = None) -> None:
        super().reset(team, seed)
        self._reach = float(self.reach if self.reach is not None else team.config.sensor.max_range)

    def assign(self, observations: Mapping[str, np.ndarray]) -> list[tuple[int, int] | None]:
        """Each robot's target frontier cell (row, col), None where no frontier is reachable for it."""
        planners, team = self.planners, self.team
        first = planners[0]
        blocked = np.zeros_like(first._wall)
        for planner in planners:
            blocked |= planner._wall | planner._given_up
        memory = np.asarray(team.coverage_memory)
        rows, cols = np.nonzero(frontier_regions(frontier_cells(memory, blocked), first.min_region))
        n = len(planners)
        if rows.size == 0:
            return [None] * n
        cell, bounds = first._cell, first._bounds
        centres = np.column_stack([bounds[0] + (cols + 0.5) * cell, bounds[1] + (rows + 0.5) * cell])
        costs = np.full((n, rows.size), np.inf)
        for i, planner in enumerate(planners):
            pose = np.asarray(team.filter.pose(i), dtype=float)
            scan = wall_scan(planner.env, observations[team.possible_agents[i]])
            sources = path_sources(planner._wall, bounds, cell, pose, scan, planner._angles)
            dist, _ = grid_paths(planner._wall, sources, cell)
            turn = np.abs((np.arctan2(centres[:, 1] - pose[1], centres[:, 0] - pose[0]) - pose[2] + np.pi) % (2 * np.pi) - np.pi)  # fmt: skip
            costs[i] = dist[rows, cols] + planner.turn_cost * turn
        chosen = utility_cost_assignment(costs, centres, self.beta, self._reach)
        return [None if t < 0 else (int(rows[t]), int(cols[t])) for t in chosen]

    def act(self, observations: Mapping[str, np.ndarray]) -> dict[str, int]:
        for planner, target in zip(self.planners, self.assign(observations)):
            planner.assigned = target
        return super().act(observations)
