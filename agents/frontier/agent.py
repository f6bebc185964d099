"""The frontier agent: the three-mode state machine (explore, revisit, relocalise) that chooses a goal and a path
to it, the bookkeeping of every control step, and the velocity commands of the waypoint controller along the
path (see the package docstring for the method)."""

from __future__ import annotations

import math
from collections.abc import Callable
from enum import Enum
from typing import Any

import gymnasium as gym
import numpy as np

from ekfslam_gym.envs.waypoint import WaypointController

from ..base import ActionKind, Agent, beam_angles, clip_action, wall_scan
from ..navigation import (
    carrot,
    frontier_cells,
    frontier_regions,
    grid_paths,
    nearest_paths,
    path_sources,
    trace_path,
    update_walls,
)
from .geometry import bearings, cell_centres, cell_of, in_reach, in_view


class Mode(str, Enum):
    """What the frontier agent is doing. ``explore``: driving to the nearest frontier; ``revisit``: no frontier
    left (or every landmark seen), driving to the seen landmark out of view the longest; ``relocalize``: the
    pose is uncertain, driving to a landmark much more certain than it. ``_plan`` moves between them: relocalise
    while the pose's std is above ``relocalize_std`` (until it falls below ``relocalize_until`` times it, or no
    landmark can help), else explore while a frontier is reachable and a landmark is unseen, else revisit."""

    EXPLORE = "explore"
    REVISIT = "revisit"
    RELOCALIZE = "relocalize"

    def __str__(self) -> str:
        return self.value


def coverage_and_bounds(env: Any) -> tuple[np.ndarray, np.ndarray]:
    """The env's coverage memory (rows along y, 1 = looked at) and the world's bounds (xmin, ymin, xmax, ymax),
    through its public read-only properties ``coverage_memory`` and ``bounds``."""
    u = env.unwrapped
    return np.asarray(u.coverage_memory), np.asarray(u.bounds, dtype=float)


class FrontierAgent(Agent):
    """Nearest-frontier exploration, then revisiting landmarks (see the package docstring for the method).

    Args:
        min_region: frontier regions smaller than this (cells) are ignored. replan_every: steps between plans.
        turn_cost: m of path that one radian of turning towards a frontier costs. lookahead: m along the path
            to the point the controller steers at. stuck_steps, stall_distance: a goal is given up when the
            robot has not moved ``stall_distance`` m in ``stuck_steps`` steps. patience: multiple of a path's
            driving time after which its goal is given up. give_up_radius: m around a given-up goal whose
            frontier cells are no longer sought. switch_margin: m by which another frontier must be nearer
            than the current goal to replace it. join: m, scan end points closer than this are one wall.
            revisit_range: m within which a revisited landmark counts as seen again. revisit_memory: the most
            recently revisited landmarks not chosen again.
            controller: keyword arguments of the ``WaypointController``. relocalize_std: m of pose position
            std above which the agent relocalises (None: never). relocalize_until: the fraction of
            relocalize_std below which it explores again. anchor_ratio: a landmark helps relocalise when its
            marginal position std is below this fraction of the pose's. home_weight: m of path cost per m that
            a frontier lies from where the episode started (0: the nearest frontier; above 0 the map grows
            outwards from the start, so the robot keeps the landmarks it mapped first in reach and its pose
            stays localised at less coverage lost than relocalising costs; a teacher's setting).

    The defaults are the best of one-at-a-time sweeps on the training seeds of EKFSLAM-v0 and EKFSLAM-Loop-v0
    (docs/research-log.md, *How the planners' defaults were chosen*, has the ranges and the figures).
    """

    name = "frontier"
    action_kind = ActionKind.VELOCITY

    def __init__(
        self,
        min_region: int = 3,
        replan_every: int = 10,
        turn_cost: float = 1.5,
        lookahead: float = 1.0,
        stuck_steps: int = 30,
        stall_distance: float = 0.5,
        patience: float = 3.0,
        give_up_radius: float = 1.0,
        switch_margin: float = 1.0,
        join: float = 1.5,
        revisit_range: float = 3.0,
        revisit_memory: int = 3,
        controller: dict[str, Any] | None = None,
        relocalize_std: float | None = None,
        relocalize_until: float = 0.6,
        anchor_ratio: float = 0.7,
        home_weight: float = 0.0,
    ) -> None:
        super().__init__()
        if not home_weight >= 0:
            raise ValueError(f"need home_weight >= 0, got {home_weight}")
        self.home_weight = float(home_weight)
        if min_region < 1 or replan_every < 1 or stuck_steps < 1 or lookahead <= 0 or patience <= 0:
            raise ValueError(
                "need min_region, replan_every, stuck_steps >= 1 and lookahead, patience > 0, got "
                f"{min_region}, {replan_every}, {stuck_steps}, {lookahead}, {patience}"
            )
        if relocalize_std is not None and not (
            relocalize_std > 0 and 0 < relocalize_until < 1 and 0 < anchor_ratio <= 1
        ):
            raise ValueError(
                "need relocalize_std > 0, 0 < relocalize_until < 1 and 0 < anchor_ratio <= 1, got "
                f"{relocalize_std}, {relocalize_until}, {anchor_ratio}"
            )
        self.relocalize_std = None if relocalize_std is None else float(relocalize_std)
        self.relocalize_until = float(relocalize_until)
        self.anchor_ratio = float(anchor_ratio)
        self.min_region = int(min_region)
        self.replan_every = int(replan_every)
        self.turn_cost = float(turn_cost)
        self.lookahead = float(lookahead)
        self.stuck_steps = int(stuck_steps)
        self.stall_distance = float(stall_distance)
        self.patience = float(patience)
        self.give_up_radius = float(give_up_radius)
        self.switch_margin = float(switch_margin)
        self.join = float(join)
        self.revisit_range = float(revisit_range)
        self.revisit_memory = int(revisit_memory)
        self.controller_kwargs = dict(controller or {})

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        cfg = self.env.config
        memory, bounds = coverage_and_bounds(self.env)
        self._bounds = bounds
        self._cell = float(cfg.observation.memory_resolution)
        self._wall = np.zeros(memory.shape, dtype=np.bool_)
        self._given_up = np.zeros(memory.shape, dtype=np.bool_)
        self._angles = beam_angles(cfg.sensor.n_beams)
        self._scan_max = cfg.sensor.scan_max_range - 1e-6
        self._controller = WaypointController.from_config(cfg, **self.controller_kwargs)
        self._step_time = cfg.robot.v_max * cfg.dt  # m driven per control step at full speed
        self._half_fov = 0.5 * cfg.sensor.fov
        self._max_range = cfg.sensor.max_range
        self._goal: tuple[int, int] | None = None  # the frontier cell (row, col) being driven to
        self._landmark = -1  # the landmark being revisited, -1 while exploring
        self._recent: list[int] = []
        self._path = np.zeros((0, 2))
        self._index = 0
        self._since_plan = 0
        self._t = 0
        self._last_view = np.zeros(self.env.filter.n_landmarks)
        self._steps_on_goal = 0
        self._budget = 0.0
        self._anchor = (float(self.env.filter.pose[0]), float(self.env.filter.pose[1]))
        self._home = self._anchor
        self._stalled = 0
        self.mode = Mode.EXPLORE
        self._relocalizing = False

    # ------------------------------------------------------------------ the grid
    def _cell_of(self, x: float, y: float) -> tuple[int, int]:
        return cell_of(x, y, self._bounds[0], self._bounds[1], self._cell, self._wall.shape)

    def _path_to(self, parent: np.ndarray, row: int, col: int) -> np.ndarray:
        """Cell centres (k, 2) from the source to (row, col), by following the parents."""
        return trace_path(parent, self._wall.shape[1], row, col, self._bounds[0], self._bounds[1], self._cell)

    # ------------------------------------------------------------------ planning: the modes
    def frontiers(self) -> np.ndarray:
        """The frontier cells now sought (bool, the memory's shape): in large enough regions, not walls and not
        given up."""
        memory, _ = coverage_and_bounds(self.env)
        blocked = self._wall | self._given_up
        return frontier_regions(frontier_cells(memory, blocked), self.min_region)

    def pose_std(self) -> float:
        """The pose estimate's position standard deviation sqrt(tr Sigma_xy), m."""
        cov = np.asarray(self.env.filter.pose_cov)
        return math.sqrt(cov[0, 0] + cov[1, 1])

    def _relocalize_switch(self) -> bool:
        """Whether the pose's std has crossed the threshold that starts or ends relocalising."""
        if self.relocalize_std is None:
            return False
        std = self.pose_std()
        if self._relocalizing:
            return std < self.relocalize_until * self.relocalize_std
        return std > self.relocalize_std

    def _plan(self, pose: np.ndarray, scan: np.ndarray) -> None:
        """Choose the mode, the goal and the path to it (the transitions are ``Mode``'s)."""
        sources = path_sources(self._wall, self._bounds, self._cell, pose, scan, self._angles)
        self._since_plan = 0
        if self._relocalize_switch():
            self._relocalizing = not self._relocalizing
            self._landmark = -1
        full = None  # the whole grid's search, once one was needed
        if self._relocalizing:
            self._goal = None
            full = grid_paths(self._wall, sources, self._cell)
            if self._plan_relocalize(pose, *full):
                self._index = 0
                return
            self._relocalizing = False  # no landmark certain enough to help: explore on, on the same search
        frontier = self.frontiers()
        every_landmark_seen = bool(np.all(np.asarray(self.env.filter.observed)))
        rows, cols = np.nonzero(frontier)
        exploring = rows.size > 0 and not every_landmark_seen
        if exploring:
            turn, home = self._goal_terms(pose, rows, cols)
            paths = full
            if paths is None:
                # only the frontier cells within switch_margin of the cheapest matter below: search no further
                extra = np.full(frontier.shape, np.inf)
                extra[rows, cols] = turn if home is None else turn + home
                paths = nearest_paths(self._wall, sources, self._cell, extra, self.switch_margin)
            # the full search holds the bounded one's paths exactly, and the goal chosen on either is the same
            dist, parent = paths
            reached = np.isfinite(dist[rows, cols])
            exploring = bool(reached.any())
        else:
            dist, parent = full or grid_paths(self._wall, sources, self._cell)
        if exploring:
            self._plan_explore(frontier, rows[reached], cols[reached], dist, parent, turn[reached],
                               None if home is None else home[reached])  # fmt: skip
        else:  # no frontier reachable, or nothing left to discover: the search above was the full one
            self._goal = None
            self._plan_revisit(pose, dist, parent)
        self._index = 0

    def _plan_explore(
        self,
        frontier: np.ndarray,
        rows: np.ndarray,
        cols: np.ndarray,
        dist: np.ndarray,
        parent: np.ndarray,
        turn: np.ndarray,
        home: np.ndarray | None,
    ) -> None:
        """Drive to the cheapest reachable frontier cell (rows, cols), keeping the current goal unless another is
        ``switch_margin`` m cheaper."""
        self.mode = Mode.EXPLORE
        self._landmark = -1
        cost = dist[rows, cols] + turn
        if home is not None:
            cost = cost + home
        best = int(np.argmin(cost))
        goal = (int(rows[best]), int(cols[best]))
        if (
            self._goal is not None
            and self._goal != goal
            and frontier[self._goal]
            and np.isfinite(dist[self._goal])
        ):
            current = np.flatnonzero((rows == self._goal[0]) & (cols == self._goal[1]))[0]
            if cost[current] <= cost[best] + self.switch_margin:
                goal = self._goal  # keep the goal unless another is clearly nearer
        if goal != self._goal:
            self._goal = goal
            self._steps_on_goal = 0
            self._budget = self.patience * (dist[goal] + self._cell) / self._step_time + 2 * self.stuck_steps
        self._path = self._path_to(parent, *goal)

    def _goal_terms(self, pose: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, Any]:
        """What the frontier cells (rows, cols) cost on top of their path (m): ``turn_cost`` m per radian of
        turning to face them, and ``home_weight`` m per m they lie from the start (None without it); a cell's
        cost is its path plus the first, plus the second."""
        xs, ys = cell_centres(rows, cols, self._bounds[0], self._bounds[1], self._cell)
        turn = bearings(pose, xs, ys)
        home = (
            self.home_weight * np.hypot(xs - self._home[0], ys - self._home[1]) if self.home_weight else None
        )
        return self.turn_cost * turn, home

    def _plan_revisit(self, pose: np.ndarray, dist: np.ndarray, parent: np.ndarray) -> None:
        """No frontier left: drive to the seen landmark out of view the longest."""
        self.mode = Mode.REVISIT

        def score(covs: np.ndarray, path: np.ndarray) -> np.ndarray:
            return self._t - self._last_view + 1.0

        if not self._drive_to_landmark(pose, dist, parent, score):
            self._path = np.zeros((0, 2))

    def _plan_relocalize(self, pose: np.ndarray, dist: np.ndarray, parent: np.ndarray) -> bool:
        """The pose is uncertain: drive to the nearest seen landmark much more certain than the pose. False
        when there is none."""
        self.mode = Mode.RELOCALIZE
        limit = (self.anchor_ratio * self.pose_std()) ** 2

        def score(covs: np.ndarray, path: np.ndarray) -> np.ndarray:
            return np.where(covs[:, 0, 0] + covs[:, 1, 1] < limit, -path, -np.inf)

        return self._drive_to_landmark(pose, dist, parent, score)

    def _drive_to_landmark(
        self,
        pose: np.ndarray,
        dist: np.ndarray,
        parent: np.ndarray,
        score: Callable[[np.ndarray, np.ndarray], np.ndarray],
    ) -> bool:
        """Keep driving to the landmark being revisited while it is not yet in view; else pick the reachable
        seen landmark (not among the most recent) with the highest ``score(covs, path lengths)``. Sets the
        path; False when no landmark qualifies."""
        ekf = self.env.filter
        landmarks = np.asarray(ekf.landmarks)
        if self._landmark < 0 or not self._landmark_pending(pose, landmarks):
            if self._landmark >= 0:
                self._recent = (self._recent + [self._landmark])[-self.revisit_memory :]
            cells = [self._cell_of(*p) for p in landmarks]
            path = np.array([dist[r, c] for r, c in cells])
            value = np.full(len(landmarks), -np.inf)
            ok = np.asarray(ekf.observed) & np.isfinite(path)
            value[ok] = np.asarray(score(ekf.landmark_covs(), path), dtype=float)[ok]
            value[self._recent] = -np.inf
            if not np.isfinite(value).any():
                self._landmark = -1
                return False
            self._landmark = int(np.argmax(value))
            self._steps_on_goal = 0
            r, c = cells[self._landmark]
            self._budget = self.patience * (dist[r, c] + self._cell) / self._step_time + 2 * self.stuck_steps
        r, c = self._cell_of(*landmarks[self._landmark])
        self._path = self._path_to(parent, r, c)
        return True

    def _landmark_pending(self, pose: np.ndarray, landmarks: np.ndarray) -> bool:
        """Whether the revisited landmark is not yet within revisit_range m in the field of view."""
        return not in_reach(pose, landmarks[self._landmark], self.revisit_range, self._half_fov)

    def _mark_views(self, pose: np.ndarray) -> None:
        """Stamp the landmarks whose estimates lie in the sensor's range and field of view now."""
        inside = in_view(pose, np.asarray(self.env.filter.landmarks), self._max_range, self._half_fov)
        self._last_view[inside & np.asarray(self.env.filter.observed)] = self._t

    def _give_up(self) -> None:
        """Stop seeking the current goal: the frontier cells around it, or the landmark for a while."""
        if self._goal is not None:
            r, c = self._goal
            k = int(math.ceil(self.give_up_radius / self._cell))
            ny, nx = self._given_up.shape
            rows, cols = np.ogrid[max(r - k, 0) : min(r + k + 1, ny), max(c - k, 0) : min(c + k + 1, nx)]
            near = (rows - r) ** 2 + (cols - c) ** 2 <= k * k
            self._given_up[max(r - k, 0) : min(r + k + 1, ny), max(c - k, 0) : min(c + k + 1, nx)] |= near
            self._goal = None
        elif self._landmark >= 0:
            self._recent = (self._recent + [self._landmark])[-self.revisit_memory :]
            self._landmark = -1

    def _needs_plan(self, pose: np.ndarray) -> bool:
        if self._since_plan >= self.replan_every or len(self._path) == 0 or self._relocalize_switch():
            return True
        if self._goal is not None:
            memory, _ = coverage_and_bounds(self.env)
            return bool(memory[self._goal] > 0)  # looked at: no longer a frontier
        if self._landmark >= 0:
            return not self._landmark_pending(pose, np.asarray(self.env.filter.landmarks))
        return False

    # ------------------------------------------------------------------ acting
    def _advance(self, pose: np.ndarray, scan: np.ndarray, steps: int = 1) -> int | None:
        """The bookkeeping of ``steps`` control steps driven since the last call (wall memory, landmark views,
        stall and give-up checks, replanning), then the index along the path of the point nearest the robot
        (progress), or None when there is nothing reachable to do."""
        b = self._bounds
        update_walls(
            self._wall, b[0], b[1], self._cell, pose[0], pose[1], pose[2], self._angles, scan, self._scan_max,
            self.join,
        )  # fmt: skip
        self._t += steps
        self._mark_views(pose)
        if math.hypot(pose[0] - self._anchor[0], pose[1] - self._anchor[1]) > self.stall_distance:
            self._anchor = (pose[0], pose[1])
            self._stalled = 0
        else:
            self._stalled += steps
        if self._stalled >= self.stuck_steps or self._steps_on_goal > self._budget:
            self._give_up()
            self._stalled = 0
            self._path = np.zeros((0, 2))
        if self._needs_plan(pose):
            self._plan(pose, scan)
        self._since_plan += steps
        self._steps_on_goal += steps
        if len(self._path) == 0:
            return None
        self._index += int(
            np.argmin(np.hypot(*(self._path[self._index :] - pose[:2]).T)[: max(1, int(4 / self._cell))])
        )
        return self._index

    def _carrot_index(self, pose: np.ndarray, lookahead: float) -> int:
        """The furthest path point from the progress index on within ``lookahead`` m in a free line of sight."""
        b = self._bounds
        return int(
            carrot(self._path, self._index, self._wall, b[0], b[1], self._cell, pose[0], pose[1], lookahead)
        )

    def act(self, observation: Any) -> np.ndarray:
        pose = np.asarray(self.env.filter.pose, dtype=float)
        scan = wall_scan(self.env, observation)
        if self._advance(pose, scan) is None:  # nothing reachable to do: look around
            return clip_action(0.0, 1.0)
        target = self._carrot_index(pose, self.lookahead)
        command = self._controller.command(pose, self._path[target], scan)
        while command.reached and target + 1 < len(self._path):  # a reached point on the way: steer past it
            target += 1
            self._index = target
            command = self._controller.command(pose, self._path[target], scan)
        if command.reached:
            self._path = np.zeros((0, 2))  # at the goal: plan afresh next step
        return clip_action(command.v, command.omega)

    def __repr__(self) -> str:
        return f"FrontierAgent(min_region={self.min_region}, replan_every={self.replan_every})"
