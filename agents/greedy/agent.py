"""The greedy information-gain agent: plans over motion primitives every few steps (see the package docstring)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from ..base import Agent, beam_angles, clip_action, wall_scan
from ..navigation import count_new, frontier_field, mark_seen, update_walls
from ..navigation.veto import WALL_JOIN, arc_vetoed, scan_geometry, to_world
from .rollout import DEFAULT_PRIMITIVES, discovery_nats, primitive_controls, rollout, rollout_gain


class GreedyInfoGainAgent(Agent):
    """Greedy D-optimal active SLAM over motion primitives (see the module docstring for the method).

    Uses: the env's filter (its belief), the config's sensor, odometry-noise and robot parameters, the world's
    bounds, and the observation's wall scan. Not the walls' geometry, the true poses or the true landmarks.

    Args:
        primitives: (v / v_max, omega / omega_max) pairs, each held for ``horizon`` steps.
        horizon: steps per rollout. replan_every: steps executed before planning again.
        cell: coverage grid resolution (m). discovery_weight: multiplier of the discovery term (1 = the
            expected information of the expected discoveries). frontier_weight: nats per metre of progress
            towards the unexplored. lookahead: m ahead of the robot where that progress is measured.
            frontier_scale: m of path a thin unexplored region costs per e-fold of thinness. clearance: m
            kept between the robot's edge and the scanned walls. give_up: views hidden behind remembered
            walls after which an unlooked-at cell is no longer sought. commitment: nats added to the
            primitive being executed when replanning. depth: primitives planned ahead, 1 or 2 (2: each
            first primitive also earns ``discount`` times the best score of a second one driven from where
            it ends, on the belief, wall scan and coverage it leaves; about ten times the cost of a plan).

    The defaults are the best of sweeps in EKFSLAM-v0 on training seeds (docs/research-log.md, *How the
    planners' defaults were chosen*).
    """

    name = "greedy"

    def __init__(
        self,
        primitives: Sequence[tuple[float, float]] = DEFAULT_PRIMITIVES,
        horizon: int = 15,
        replan_every: int = 3,
        cell: float = 0.5,
        discovery_weight: float = 1.0,
        frontier_weight: float = 2.0,
        clearance: float = 0.15,
        lookahead: float = 1.0,
        frontier_scale: float = 2.0,
        give_up: int = 20,
        commitment: float = 1.0,
        depth: int = 1,
        discount: float = 1.0,
    ) -> None:
        super().__init__()
        if isinstance(depth, bool) or depth not in (1, 2):
            raise ValueError(f"depth (primitives planned ahead) must be 1 or 2, got {depth!r}")
        if not 0.0 <= discount <= 1.0:
            raise ValueError(f"discount must lie in [0, 1], got {discount!r}")
        if horizon < 1 or replan_every < 1 or cell <= 0:
            raise ValueError(
                f"need horizon >= 1, replan_every >= 1 and cell > 0, got {horizon}, {replan_every}, {cell}"
            )
        self.primitives = np.asarray(primitives, dtype=float).reshape(-1, 2)
        self.horizon = int(horizon)
        self.replan_every = int(replan_every)
        self.cell = float(cell)
        self.discovery_weight = float(discovery_weight)
        self.frontier_weight = float(frontier_weight)
        self.clearance = float(clearance)
        self.lookahead = float(lookahead)
        self.frontier_scale = float(frontier_scale)
        self.give_up = int(give_up)
        self.commitment = float(commitment)
        self.depth = int(depth)
        self.discount = float(discount)
        self.last_scores: np.ndarray | None = None  # per primitive, -inf when vetoed (for inspection)

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        super().reset(env, seed)
        u = self.env
        cfg = u.config
        ekf = u.filter
        sensor = cfg.sensor
        self._min_range = max(sensor.min_range, ekf.min_range)
        self._max_range = sensor.max_range
        self._fov = sensor.fov
        self._scan_max = sensor.scan_max_range
        self._angles = beam_angles(sensor.n_beams)
        self._safe = cfg.robot.radius + self.clearance
        # the noise model of the filter's odometry, which the rollouts predict with
        self._motion_noise = noise = {
            "odometry": cfg.odometry, "velocity": u.world.velocity_noise, "wheels": u.world.wheel_noise
        }[ekf.motion_model]  # fmt: skip
        self._plans = []
        for v, w in self.primitives:
            controls, covs, rel = primitive_controls(
                v * cfg.robot.v_max, w * cfg.robot.omega_max, cfg.dt, self.horizon, ekf.motion_model, noise
            )
            self._plans.append((controls, covs, rel))
        self._bounds = np.asarray(u.world.layout.bounds, dtype=float)  # the world's extent only
        nx = max(1, int(math.ceil((self._bounds[2] - self._bounds[0]) / self.cell)))
        ny = max(1, int(math.ceil((self._bounds[3] - self._bounds[1]) / self.cell)))
        self._seen = np.zeros((ny, nx), dtype=np.bool_)
        self._wall = np.zeros((ny, nx), dtype=np.bool_)
        self._hidden = np.zeros((ny, nx), dtype=np.int64)
        self._stamp = np.zeros((ny, nx), dtype=np.int64)
        self._tag = 0
        self._nats = discovery_nats(
            ekf.landmark_prior, ekf.measurement_noise, self._min_range, self._max_range
        )
        self._current = 0
        self._left = 0

    # ------------------------------------------------------------------ pieces
    def _vetoed(self, rel: np.ndarray, pose: np.ndarray, points: np.ndarray, segments: np.ndarray) -> bool:
        return arc_vetoed(rel, pose, points, segments, self._safe, self._bounds, self.env.config.robot.radius)

    def vetoed_primitives(self, scan: np.ndarray, pose: np.ndarray) -> np.ndarray:
        """Which primitives (bool per primitive) the wall scan (m, per beam) and the bounds rule out at ``pose``."""
        points, segments = scan_geometry(np.asarray(scan, dtype=float), self._angles, self._scan_max)
        pose = np.asarray(pose, dtype=float)
        return np.array([self._vetoed(rel, pose, points, segments) for _, _, rel in self._plans])

    def expected_gain(self, index: int) -> float:
        """Expected log det drop (nats) of primitive ``index`` from the env's current belief."""
        controls, covs, _ = self._plans[index]
        return rollout_gain(self.env.filter, controls, covs, self._min_range, self._max_range, self._fov)

    def _plan(self, pose: np.ndarray, points: np.ndarray, segments: np.ndarray) -> int:
        ekf = self.env.filter
        n_unseen = int(ekf.n_landmarks - np.count_nonzero(ekf.observed))
        open_cells = self._open_unlooked()
        done = ~open_cells  # looked at, walls, or given up as hidden: nothing to discover there
        n_unlooked = int(done.size - np.count_nonzero(done))
        explore = n_unseen > 0 and n_unlooked > 0
        per_cell = self._nats * n_unseen / max(n_unlooked, 1)  # expected nats of discovery per unlooked cell
        field = self._frontier_field(open_cells) if explore and self.frontier_weight else None
        terms = (done, per_cell, field, explore)
        scores = np.full(len(self._plans), -np.inf)
        for i, (controls, covs, rel) in enumerate(self._plans):
            if self._vetoed(rel, pose, points, segments):
                continue
            sim = rollout(ekf, controls, covs, self._min_range, self._max_range, self._fov)
            score = self._step_score(float(ekf.log_det - sim.log_det), rel, pose, *terms)
            if self.depth == 2:
                score += self.discount * self._best_second(sim, rel, pose, points, segments, *terms)
            scores[i] = score + (self.commitment if i == self._current else 0.0)
        self.last_scores = scores
        return int(np.argmax(scores)) if np.isfinite(scores).any() else -1

    def _step_score(
        self, gain: float, rel: np.ndarray, start: np.ndarray, done: np.ndarray, per_cell: float,
        field: np.ndarray | None, explore: bool,
    ) -> float:  # fmt: skip
        """``gain`` (nats) plus the discovery and frontier terms of driving ``rel`` from the world pose
        ``start``: the cells counted are those not ``done``, stamped with ``self._tag`` (see the package
        docstring)."""
        score = gain
        if explore:
            b = self._bounds
            world = to_world(rel[1:], start)
            self._tag += 1
            new = count_new(
                done,
                self._stamp,
                self._tag,
                b[0],
                b[1],
                self.cell,
                world,
                0.0,
                self._max_range,
                0.5 * self._fov,
            )
            score += self.discovery_weight * per_cell * new
            if field is not None:
                here, there = self._lookup(field, start), self._lookup(field, world[-1])
                if np.isfinite(here) and np.isfinite(there):
                    score += self.frontier_weight * (here - there)
        return score

    def _best_second(
        self, sim: Any, first: np.ndarray, pose: np.ndarray, points: np.ndarray, segments: np.ndarray,
        done: np.ndarray, per_cell: float, field: np.ndarray | None, explore: bool,
    ) -> float:  # fmt: skip
        """The best score of a second primitive driven from where the first (relative poses ``first``, just
        scored by ``_step_score``) ends: on the first's rolled-forward belief ``sim``, vetoed against the same
        wall scan, discovering only cells the first left unlooked-at (its stamped cells count as done). The
        frontier field is not recomputed. 0 when every second primitive is vetoed."""
        end = first[-1]
        start = to_world(end[None], pose)[0]
        if explore:
            done = done | (self._stamp == self._tag)
        best = -np.inf
        for controls, covs, rel in self._plans:
            if self._vetoed(to_world(rel, end), pose, points, segments):  # the path in the robot's frame now
                continue
            gain = rollout_gain(sim, controls, covs, self._min_range, self._max_range, self._fov)
            best = max(best, self._step_score(gain, rel, start, done, per_cell, field, explore))
        return best if np.isfinite(best) else 0.0

    def _open_unlooked(self) -> np.ndarray:
        """Unlooked-at cells still worth looking at: not walls, and not hidden behind remembered walls in
        ``give_up`` views (the inside of the loop layout's central block, say, would otherwise pull the robot
        into the wall for ever; a 16-beam scan is too coarse to map walls well enough to seal such regions)."""
        return ~self._seen & ~self._wall & (self._hidden < self.give_up)

    def _frontier_field(self, open_cells: np.ndarray) -> np.ndarray:
        return frontier_field(open_cells, self._wall, self.cell, self.frontier_scale)

    def _lookup(self, field: np.ndarray, pose: np.ndarray) -> float:
        """The field at the point ``lookahead`` m ahead of ``pose`` (so facing the unexplored counts)."""
        b = self._bounds
        x = pose[0] + self.lookahead * math.cos(pose[2])
        y = pose[1] + self.lookahead * math.sin(pose[2])
        col = min(max(int((x - b[0]) / self.cell), 0), field.shape[1] - 1)
        row = min(max(int((y - b[1]) / self.cell), 0), field.shape[0] - 1)
        return float(field[row, col])

    # ------------------------------------------------------------------ acting
    def act(self, observation: Any) -> np.ndarray:
        pose = np.asarray(self.env.filter.pose, dtype=float)
        scan = wall_scan(self.env, observation)
        b = self._bounds
        # Walls first, so this scan's surfaces already hide what lies behind them.
        update_walls(
            self._wall, b[0], b[1], self.cell, pose[0], pose[1], pose[2], self._angles, scan,
            self._scan_max - 1e-6, WALL_JOIN,
        )  # fmt: skip
        mark_seen(
            self._seen, self._hidden, self._wall, b[0], b[1], self.cell, pose[0], pose[1], pose[2], self._max_range,
            0.5 * self._fov,
        )  # fmt: skip
        points, segments = scan_geometry(scan, self._angles, self._scan_max)
        if (
            self._current < 0
            or self._left <= 0
            or self._vetoed(self._plans[self._current][2], pose, points, segments)
        ):
            self._current = self._plan(pose, points, segments)
            self._left = self.replan_every
        self._left -= 1
        if self._current < 0:  # every primitive vetoed: turn in place towards the more open side
            left = scan[(self._angles > 0) & (self._angles < math.pi)].sum()
            right = scan[self._angles > math.pi].sum()
            return clip_action(0.0, 1.0 if left >= right else -1.0)
        v, w = self.primitives[self._current]
        return clip_action(v, w)

    def __repr__(self) -> str:
        depth = f", depth={self.depth}, discount={self.discount}" if self.depth != 1 else ""
        return f"{type(self).__name__}(horizon={self.horizon}, replan_every={self.replan_every}{depth})"


class GreedyLookaheadAgent(GreedyInfoGainAgent):
    """The greedy planner looking two primitives ahead (``depth=2``): the registry's ``greedy2``, so the
    evaluate command line can compare it with ``greedy`` in one run."""

    name = "greedy2"

    def __init__(self, depth: int = 2, **kwargs: Any) -> None:
        super().__init__(depth=depth, **kwargs)
