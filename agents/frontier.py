"""Nearest-frontier exploration (Yamauchi 1997, "A frontier-based approach for autonomous exploration"), the
standard baseline of the exploration literature, on the env's coverage memory.

Frontiers: cells of the coverage memory not yet looked at (and not known to be walls) that border a looked-at
cell, grouped into 8-connected regions; regions smaller than ``min_region`` cells are dropped (slivers along
walls). The goal is the frontier cell nearest by *path* distance, plus ``turn_cost`` m per radian the robot
must first turn to face it (with a field of view of half a circle, the frontier behind the robot is cheap
in metres but not in time). The path is a shortest path (Dijkstra, 8-connected) over the memory grid around
the walls the agent has mapped, searched only as far as the cheapest frontier and those within
``switch_margin`` of it need (``nearest_paths``: the same paths, bit for bit, at about half the cost of a
search of the whole grid on EKFSLAM-Large-v0); the waypoint controller (``ekfslam_gym.envs.waypoint``)
steers at the furthest point of it within ``lookahead`` m that no mapped wall hides. The agent plans again
when the goal has been looked at, every ``replan_every`` steps (keeping its goal unless another is
``switch_margin`` m nearer), or when it gives up on the goal.

Walls: the coverage memory ignores walls (it records where the sensor pointed), but the loop's central block
and the rooms' walls must be gone around, so the agent keeps an occupancy-style wall memory on the same grid
from the observation's wall scan, as the greedy planner does: each beam clears the cells it crosses; its end
point, and the surface joining it to a neighbouring end point closer than ``join`` m, mark walls. Unmapped
cells count as free (the optimistic assumption of planning in unknown space). A path starts in the robot's
cell, or, when that cell holds a wall (the robot is next to one), in the neighbouring cells the scan shows
on the robot's side of it. A goal that cannot be reached (the robot stalls, moving less than
``stall_distance`` m in ``stuck_steps`` steps, or the goal takes more than ``patience`` times its path's
driving time) is given up with the frontier cells within ``give_up_radius`` m of it, so a gap in the mapped
walls of a closed block is tried once, not forever.

Revisiting: when no frontier is left, or every landmark the filter carries has been seen (its state has one
slot per landmark, so nothing is left to discover), the agent improves the map it has (Thrun, Burgard & Fox,
*Probabilistic Robotics*, ch. 17: re-observing mapped landmarks to close loops). It drives to the seen
landmark whose estimate has been out of the sensor's range and field of view the longest until that landmark
is within ``revisit_range`` m in the field of view, then picks the next, skipping the ``revisit_memory`` most
recent. (Choosing the landmark of largest marginal covariance instead did worse, by 4 nats of final map log det
in EKFSLAM-v0 and 10 in the loop, and was removed; docs/results.md keeps the record.)

Active loop closing (Stachniss, Hahnel & Burgard 2004, "Exploration with active loop-closing for FastSLAM";
off by default): with ``relocalize_std`` set, when the pose estimate's position standard deviation
sqrt(tr Sigma_xy) exceeds it, the agent stops exploring and drives to the nearest (by path) seen landmark
that is much more certain than the pose (marginal position std below ``anchor_ratio`` times the pose's), one
after another, until the pose's std falls below ``relocalize_until`` times ``relocalize_std``. Exploring from
an uncertain pose places every new landmark as uncertainly, so this trades landmarks seen for an accurate
map.

Uses only the belief: the filter's mean and covariance, the coverage memory, the wall scan, the config and the
world's bounds; never the true map or pose.
"""

from __future__ import annotations

import heapq
import math
from typing import Any

import gymnasium as gym
import numpy as np
from numba import njit
from scipy import ndimage

from ekfslam_gym.envs.actions import PRIMITIVES
from ekfslam_gym.envs.waypoint import WaypointController

from .base import Agent, beam_angles, clip_action, wall_scan
from .greedy.grid import update_walls
from .greedy.rollout import arc_poses
from .greedy.veto import arc_vetoed, scan_geometry

EIGHT_NEIGHBOURS = np.ones((3, 3), dtype=bool)


def coverage_and_bounds(env: Any) -> tuple[np.ndarray, np.ndarray]:
    """The env's coverage memory (rows along y, 1 = looked at) and the world's bounds (xmin, ymin, xmax, ymax).

    Through the env's public read-only properties where it has them; the fallback to its private attributes is
    for envs from before those properties and can be deleted with them.
    """
    u = env.unwrapped
    if hasattr(type(u), "coverage_memory") and hasattr(type(u), "bounds"):
        return np.asarray(u.coverage_memory), np.asarray(u.bounds, dtype=float)
    return u._memory, np.asarray(u._bounds, dtype=float)


def frontier_cells(memory: np.ndarray, blocked: np.ndarray) -> np.ndarray:
    """Frontier cells (bool, the memory's shape): not looked at, not ``blocked``, with a looked-at 4-neighbour."""
    looked = np.asarray(memory) > 0
    near = np.zeros_like(looked)
    near[1:, :] |= looked[:-1, :]
    near[:-1, :] |= looked[1:, :]
    near[:, 1:] |= looked[:, :-1]
    near[:, :-1] |= looked[:, 1:]
    return near & ~looked & ~np.asarray(blocked, dtype=bool)


def frontier_regions(frontier: np.ndarray, min_size: int) -> np.ndarray:
    """The frontier cells in 8-connected regions of at least ``min_size`` cells (bool, same shape)."""
    labels, count = ndimage.label(frontier, structure=EIGHT_NEIGHBOURS)
    if count == 0:
        return np.zeros_like(frontier, dtype=bool)
    sizes = np.bincount(labels.ravel())
    keep = sizes >= min_size
    keep[0] = False
    return keep[labels]


@njit(cache=True)
def grid_paths(blocked, start_cost, cell):
    """Shortest path lengths (m) over the cells not ``blocked``, 8-connected with no corner cut past a blocked
    cell (Dijkstra), from every cell with a finite ``start_cost`` (its cost at the start; the sources may be
    blocked themselves). Returns (distances (ny, nx), inf where unreachable; parents (ny * nx,) flat indices,
    -1 at the sources and where unreachable)."""
    target_cost = np.full(blocked.shape, np.inf)
    return nearest_paths(blocked, start_cost, cell, target_cost, 0.0)


@njit(cache=True)
def nearest_paths(blocked, start_cost, cell, target_cost, margin):
    """``grid_paths`` that stops once no cell left can be a target costing less than the cheapest found plus
    ``margin``: a target's cost is its distance plus its ``target_cost`` (>= 0; inf where a cell is no target).

    The distances and parents it returns are ``grid_paths``' exactly, bit for bit, for every cell within the
    search (Dijkstra settles cells in order of distance, and the search is the same until it stops); the cells
    beyond it are inf and -1. So the cheapest target, and every target within ``margin`` of it, has its exact
    distance and path, while the nearest frontier costs a search of its distance's radius, not of the grid.
    With no target reached it is the full search."""
    ny, nx = blocked.shape
    n = ny * nx
    dist = start_cost.copy().reshape(n)
    extra = target_cost.reshape(n)
    parent = np.full(n, -1, dtype=np.int64)
    diagonal = cell * math.sqrt(2.0)
    heap = [(0.0, np.int64(0))]
    heap.pop()
    for u in range(n):
        if np.isfinite(dist[u]):
            heap.append((dist[u], np.int64(u)))
    heapq.heapify(heap)
    limit = np.inf  # the cheapest target's cost plus the margin (and a rounding's slack) so far
    while len(heap) > 0:
        d, u = heapq.heappop(heap)
        if d > dist[u]:
            continue
        if d > limit:  # every cell left is further than the limit: no cheaper target remains
            for v in range(n):
                if dist[v] > limit:
                    dist[v] = np.inf
                    parent[v] = -1
            break
        if d + extra[u] + margin < limit:
            limit = (d + extra[u] + margin) * (1.0 + 1e-12) + 1e-12
        row = u // nx
        col = u - row * nx
        for dr in range(-1, 2):
            r = row + dr
            if r < 0 or r >= ny:
                continue
            for dc in range(-1, 2):
                c = col + dc
                if (dr == 0 and dc == 0) or c < 0 or c >= nx or blocked[r, c]:
                    continue
                if dr != 0 and dc != 0:
                    if blocked[row + dr, col] or blocked[row, col + dc]:
                        continue
                    step = diagonal
                else:
                    step = cell
                v = r * nx + c
                if d + step < dist[v]:
                    dist[v] = d + step
                    parent[v] = u
                    heapq.heappush(heap, (d + step, v))
    return dist.reshape(ny, nx), parent


def path_sources(
    wall: np.ndarray, bounds: np.ndarray, cell: float, pose: np.ndarray, scan: np.ndarray, angles: np.ndarray
) -> np.ndarray:
    """Where paths start (the ``start_cost`` of ``grid_paths``): the robot's cell at cost 0; or, when the wall
    memory holds a wall in that cell (the robot is close to one), the free neighbouring cells on the robot's
    side of the wall, those whose centres both beams around their direction show in the open, each at its
    straight-line distance. From the wall's cell itself a path could lead through the wall to its far side."""
    ny, nx = wall.shape
    col = min(max(int(math.floor((pose[0] - bounds[0]) / cell)), 0), nx - 1)
    row = min(max(int(math.floor((pose[1] - bounds[1]) / cell)), 0), ny - 1)
    cost = np.full(wall.shape, np.inf)
    if not wall[row, col]:
        cost[row, col] = 0.0
        return cost
    n = len(angles)
    width = 2.0 * math.pi / n
    for r in range(max(row - 1, 0), min(row + 2, ny)):
        for c in range(max(col - 1, 0), min(col + 2, nx)):
            if wall[r, c]:
                continue
            cx, cy = bounds[0] + (c + 0.5) * cell, bounds[1] + (r + 0.5) * cell
            distance = math.hypot(cx - pose[0], cy - pose[1])
            beam = ((math.atan2(cy - pose[1], cx - pose[0]) - pose[2]) % (2.0 * math.pi)) / width
            below = int(math.floor(beam)) % n
            if min(scan[below], scan[(below + 1) % n]) >= distance:
                cost[r, c] = distance
    if not np.isfinite(cost).any():
        cost[row, col] = 0.0
    return cost


@njit(cache=True)
def _line_is_free(wall, xmin, ymin, cell, x0, y0, x1, y1):
    """Whether the segment crosses no wall cell (sampled every quarter cell; the start cell is not checked)."""
    ny, nx = wall.shape
    c0 = int(math.floor((x0 - xmin) / cell))
    r0 = int(math.floor((y0 - ymin) / cell))
    n = int(math.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2) / (0.25 * cell)) + 1
    for i in range(1, n + 1):
        t = i / n
        col = int(math.floor((x0 + t * (x1 - x0) - xmin) / cell))
        row = int(math.floor((y0 + t * (y1 - y0) - ymin) / cell))
        if (row != r0 or col != c0) and 0 <= row < ny and 0 <= col < nx and wall[row, col]:
            return False
    return True


@njit(cache=True)
def _carrot(path, first, wall, xmin, ymin, cell, x, y, lookahead):
    """The index of the furthest point of ``path`` (k, 2) from ``first`` on that lies within ``lookahead`` m of
    (x, y) in a straight line the wall memory leaves free (at least ``first``)."""
    best = first
    for i in range(first, path.shape[0]):
        dx, dy = path[i, 0] - x, path[i, 1] - y
        if dx * dx + dy * dy > lookahead * lookahead:
            break
        if _line_is_free(wall, xmin, ymin, cell, x, y, path[i, 0], path[i, 1]):
            best = i
    return best


class FrontierAgent(Agent):
    """Nearest-frontier exploration, then revisiting landmarks (see the module docstring for the method).

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
            stays localised at less coverage lost than relocalising costs; a teacher's setting, see
            docs/results.md).

    The defaults are the best of one-at-a-time sweeps on training seeds 0-39 of EKFSLAM-v0 and
    EKFSLAM-Loop-v0 (mean final map log det): turn_cost 0-4 m/rad (0, pure path distance, turns back and forth
    between frontiers ahead and behind and sees 0.62 of the landmarks in EKFSLAM-v0), lookahead 0.75-3.5 m
    (longer cuts corners and leaves them unexplored), min_region 1-6, replan_every 3-30, switch_margin 0-3 m,
    stuck_steps 20-50, give_up_radius 1-2 m, the stalest landmark revisited first rather than the most
    uncertain (by 4 nats in EKFSLAM-v0 and 10 in the loop). Most settings besides turn_cost and lookahead were
    within 2 nats. Active loop closing is off: on EKFSLAM-Large-v0 (seeds 20000-20019) it trades map log det
    for landmark RMSE, -182 / 0.13 m without it, -98 / 0.11 at 0.3 m, -36 / 0.098 at 0.2 m, +259 / 0.049 at
    0.1 m.
    """

    name = "frontier"

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
        self.mode = "explore"
        self._relocalizing = False

    # ------------------------------------------------------------------ geometry
    def _cell_of(self, x: float, y: float) -> tuple[int, int]:
        ny, nx = self._wall.shape
        col = min(max(int(math.floor((x - self._bounds[0]) / self._cell)), 0), nx - 1)
        row = min(max(int(math.floor((y - self._bounds[1]) / self._cell)), 0), ny - 1)
        return row, col

    def _centre(self, row: int, col: int) -> tuple[float, float]:
        return self._bounds[0] + (col + 0.5) * self._cell, self._bounds[1] + (row + 0.5) * self._cell

    def _path_to(self, parent: np.ndarray, row: int, col: int) -> np.ndarray:
        """Cell centres (k, 2) from the source to (row, col), by following the parents."""
        nx = self._wall.shape[1]
        cells = []
        u = row * nx + col
        while u >= 0:
            cells.append(u)
            u = int(parent[u])
        cells.reverse()
        rows, cols = np.divmod(np.array(cells, dtype=np.int64), nx)
        return np.column_stack(
            [self._bounds[0] + (cols + 0.5) * self._cell, self._bounds[1] + (rows + 0.5) * self._cell]
        )

    # ------------------------------------------------------------------ planning
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
            self.mode = "explore"
            self._landmark = -1
            rows, cols = rows[reached], cols[reached]
            cost = dist[rows, cols] + turn[reached]
            if home is not None:
                cost = cost + home[reached]
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
                self._budget = (
                    self.patience * (dist[goal] + self._cell) / self._step_time + 2 * self.stuck_steps
                )
            self._path = self._path_to(parent, *goal)
        else:  # no frontier reachable, or nothing left to discover: the search above was the full one
            self._goal = None
            self._plan_revisit(pose, dist, parent)
        self._index = 0

    def _goal_terms(self, pose: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, Any]:
        """What the frontier cells (rows, cols) cost on top of their path (m): ``turn_cost`` m per radian of
        turning to face them, and ``home_weight`` m per m they lie from the start (None without it); a cell's
        cost is its path plus the first, plus the second."""
        xs = self._bounds[0] + (cols + 0.5) * self._cell
        ys = self._bounds[1] + (rows + 0.5) * self._cell
        turn = np.abs((np.arctan2(ys - pose[1], xs - pose[0]) - pose[2] + np.pi) % (2 * np.pi) - np.pi)
        home = (
            self.home_weight * np.hypot(xs - self._home[0], ys - self._home[1]) if self.home_weight else None
        )
        return self.turn_cost * turn, home

    def _plan_revisit(self, pose: np.ndarray, dist: np.ndarray, parent: np.ndarray) -> None:
        """No frontier left: drive to the seen landmark out of view the longest."""
        self.mode = "revisit"

        def score(covs: np.ndarray, path: np.ndarray) -> np.ndarray:
            return self._t - self._last_view + 1.0

        if not self._drive_to_landmark(pose, dist, parent, score):
            self._path = np.zeros((0, 2))

    def _plan_relocalize(self, pose: np.ndarray, dist: np.ndarray, parent: np.ndarray) -> bool:
        """The pose is uncertain: drive to the nearest seen landmark much more certain than the pose. False
        when there is none."""
        self.mode = "relocalize"
        limit = (self.anchor_ratio * self.pose_std()) ** 2

        def score(covs: np.ndarray, path: np.ndarray) -> np.ndarray:
            return np.where(covs[:, 0, 0] + covs[:, 1, 1] < limit, -path, -np.inf)

        return self._drive_to_landmark(pose, dist, parent, score)

    def _drive_to_landmark(self, pose: np.ndarray, dist: np.ndarray, parent: np.ndarray, score: Any) -> bool:
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
        dx, dy = landmarks[self._landmark, 0] - pose[0], landmarks[self._landmark, 1] - pose[1]
        bearing = abs((math.atan2(dy, dx) - pose[2] + math.pi) % (2 * math.pi) - math.pi)
        return math.hypot(dx, dy) > self.revisit_range or bearing > self._half_fov

    def _mark_views(self, pose: np.ndarray) -> None:
        """Stamp the landmarks whose estimates lie in the sensor's range and field of view now."""
        delta = np.asarray(self.env.filter.landmarks) - pose[:2]
        bearing = np.abs((np.arctan2(delta[:, 1], delta[:, 0]) - pose[2] + np.pi) % (2 * np.pi) - np.pi)
        inside = (np.hypot(delta[:, 0], delta[:, 1]) <= self._max_range) & (bearing <= self._half_fov)
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
            _carrot(self._path, self._index, self._wall, b[0], b[1], self._cell, pose[0], pose[1], lookahead)
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


def in_robot_frame(pose: np.ndarray, point: np.ndarray) -> tuple[float, float]:
    """``point`` (world, m) as (forward, left) m relative to ``pose`` (x, y, heading)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = point[0] - pose[0], point[1] - pose[1]
    return c * dx + s * dy, -s * dx + c * dy


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
    spends one as a full one does. Counting the control steps actually driven instead (``elapsed_steps``)
    did worse: map log det IQM -559 / -546 on training seeds 0-19 / 20-39, against -562 / -561.
    ``goal_distance`` (m, at most the waypoint radius): 1.5 m, the best of 1.5, 2 and 2.5 on training seeds
    0-39 of EKFSLAM-v0 with hold 10 (final map log det IQM -562 and -561 on seeds 0-19 and 20-39, against
    -558/-556 at 2 m and -560 at 2.5 m on 0-19). A goal closer than the controller's slowing distance wastes
    the macro step: at 1.25 m, one step's drive at full speed plus a quarter metre, it was -366 on seeds
    20000-20019.
    """

    name = "frontier-waypoint"

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
    sight, among the primitives the wall scan and the world's bounds do not rule out (the greedy planner's
    veto, ``ekfslam_gym.agents.greedy.veto.arc_vetoed``, with ``clearance`` m beyond the robot's radius).

    It drives the frontier agent's path with the greedy planner's primitives, so that a Discrete policy can be
    taught nearest-frontier exploration in the interface the greedy clone acts in. Its step counters advance
    ``hold`` control steps per env step, as ``FrontierWaypointPlanner``'s do. ``goal_distance``: 1.5 m; on
    EKFSLAM-v0 with hold 10, training seeds 0-19 / 20-39, map log det IQM -564 / -564, against -565 / -563 at
    1.75 m, -568 / -561 at 2 m, -482 / -506 at 1 m (the arcs overshoot a nearer point); the greedy planner in
    the same interface scores -561 / -553 there and the velocity frontier agent -557 / -563. Adding a cost on
    the heading error at the arc's end (0.3 or 0.6 m per radian) did no better.
    """

    name = "frontier-primitives"

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

    def executed(self, index: int) -> None:
        """A learner drove primitive ``index`` instead (DAgger): nothing to note, the planner reads the pose."""

    def __repr__(self) -> str:
        return f"FrontierPrimitivesPlanner(goal_distance={self.goal_distance})"
