"""ekfslam_team_v0: a team of robots sharing one EKF-SLAM belief, paid together for the information it gains."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from pettingzoo import ParallelEnv
from pettingzoo.utils import wrappers
from pettingzoo.utils.conversions import parallel_to_aec

from .. import compiled
from ..envs.actions import make_interface
from ..envs.observation import ObservationLayout, make_memory, observation_constants
from ..envs.rewards import REWARD_NAMES, nonzero_weights, weigh
from ..filter.ekf import FilterDivergedError
from ..filter.team import TeamEKF
from ..sim.layouts import make_layout
from ..sim.odometry import WheelOdometryNoise
from . import kernels
from .config import TeamEnvConfig, build_team_config
from .observation import fill_teammates, team_observation_space
from .rewards import ROBOT_TERMS, robot_terms, team_terms
from .world import TeamWorld, team_starts

__all__ = ["TeamSLAMEnv", "env", "parallel_env", "raw_env"]


class TeamSLAMEnv(ParallelEnv):
    """Cooperative active SLAM: N robots drive so that their one shared EKF-SLAM map becomes certain.

    ## Description
    N pymunk-simulated differential-drive robots (1 to 5) move among the walls and point landmarks of a layout
    generated anew at every reset, as in ``EKFSLAM-v0`` (``world.layout``: arena, rooms, loop). Each robot has
    its own odometry and range-bearing sensor; robots collide with each other and hide landmarks from each
    other, and a robot reads its teammates' positions (range, bearing and identity) as MRCLAM's robots read
    each other's barcodes. One centralised EKF-SLAM (``ekfslam_gym.filter.team.TeamEKF``: every robot's pose and
    every landmark in one state, Fenwick, Newman & Leonard, ICRA 2002) fuses every robot's odometry, landmark
    readings and robot-to-robot readings. Each robot sees the joint belief from where it stands; the team is
    paid for the information it gains, all robots alike.

    ## Agents
    ``robot_0`` ... ``robot_{N-1}`` (``possible_agents``), all acting at every step (a parallel env; ``env()``
    is the AEC form through PettingZoo's ``parallel_to_aec``). Robot 0 starts at the layout's start pose, the
    others in a row across its heading, ``team.start_spacing`` m apart, every start known to the filter. All
    agents leave together when the episode ends.

    ## Action Space
    ``Discrete(9)`` per robot: one of the single-robot env's motion primitives
    (``ekfslam_gym.envs.actions.PRIMITIVES``), held for ``action.hold`` control steps (default 10); with
    ``action.guard`` each robot stops short of what its scan shows ahead, other robots included.

    ## Observation Space
    ``Box(-5, 5, (D,), float32)`` per robot, D = 164 + 6 x ``team.teammate_slots`` (188 by default): the
    single-robot observation of the robot's own pose belief, the shared map (its nearest landmarks, the map's
    mean ln variance, the fraction seen), its wall scan and the team's shared coverage memory around it, then its
    teammates' estimated relative positions, headings and the uncertainty of the relative position, nearest
    first (``ekfslam_gym.multi.observation``). ``env.observation_layout`` says where the single-robot parts lie.

    ## Rewards
    The same for every robot: the weighted sum (``reward`` section) of the team's terms
    (``ekfslam_gym.multi.rewards``), by default the information gain log det Sigma_{t-1} - log det Sigma_t of the
    joint covariance, less 1 per robot per control step in contact with a wall. ``info[agent]["reward_terms"]``
    holds the team's terms unweighted (``info_gain`` is the joint log det's drop, ``info[agent]["log_det"]``
    the joint log det), ``info[agent]["robot_terms"]`` the robot's own wall contacts and pose variance.

    ## Starting State
    The layout's start for robot 0, the row of teammates beside it (or, where walls are in the way, draws
    within ``team.start_spread`` m), every pose known to the filter to ``filter.pose_prior``; ``reset`` takes
    every robot's first readings, landmark and robot-to-robot, and corrects.

    ## Episode End
    Terminated for every robot when every landmark's marginal standard deviation is below ``done_std`` m, on
    any robot's wall contact if ``terminate_on_collision``, or when the filter fails numerically
    (``info[agent]["filter_failed"]``). Truncated after ``max_episode_steps`` env steps (default 50, 500 control
    steps of 0.1 s).

    ## Arguments
    ``parallel_env(n_robots=3, config=None, render_mode=None, **overrides)``: ``config`` a ``TeamEnvConfig``, a
    mapping of sections or a YAML file of them (the single-robot env's sections, ``ekfslam_gym.envs.config``,
    plus ``team``: ``ekfslam_gym.multi.config.TeamConfig``); ``overrides`` are sections on top, e.g.
    ``world={"n_landmarks": 120, "layout": "rooms"}``; ``n_robots`` sets ``team.n_robots``. Known data
    association only. A bad value raises ``ValueError`` naming the field. No render mode yet.

    ## Registered Configurations
    ``EKFSLAM-Team-v0`` in PettingZoo's registry (``pettingzoo.make("parallel", "EKFSLAM-Team-v0", n_robots=3)``,
    or ``"aec"``), registered when ``ekfslam_gym.multi`` is imported; or made by the module's functions:
    ``ekfslam_gym.multi.parallel_env``, ``env`` (AEC) and ``raw_env`` (AEC, unwrapped).
    """

    metadata = {"name": "ekfslam_team_v0", "render_modes": [], "is_parallelizable": True}

    def __init__(
        self,
        n_robots: int | None = None,
        config: TeamEnvConfig | str | Path | Mapping[str, Any] | None = None,
        render_mode: str | None = None,
        **overrides: Any,
    ) -> None:
        if render_mode is not None:
            raise ValueError(f"render_mode must be None (no render modes yet), got {render_mode!r}")
        self.config: TeamEnvConfig = build_team_config(config, n_robots, **overrides)
        self.render_mode = None
        cfg = self.config
        self.n_robots = cfg.team.n_robots
        self.possible_agents = [f"robot_{i}" for i in range(self.n_robots)]
        self.agents: list[str] = []
        self._index = {agent: i for i, agent in enumerate(self.possible_agents)}
        self._layout = ObservationLayout.from_config(cfg.observation, cfg.sensor)
        self._observation_space = team_observation_space(self._layout, cfg.team.teammate_slots)
        self._interfaces = [make_interface(cfg) for _ in range(self.n_robots)]
        self._action_space = self._interfaces[0].space
        self._constants = observation_constants(cfg.observation, cfg.sensor)
        self._weights = nonzero_weights(cfg.reward)
        self._cell_area = cfg.observation.memory_resolution**2
        self._v_max, self._omega_max = cfg.robot.v_max, cfg.robot.omega_max
        self._done_variance = cfg.done_std**2 if cfg.done_std > 0 else -math.inf
        self._hold = cfg.action.hold
        self.np_random, self.np_random_seed = seeding.np_random()
        self._ekf: TeamEKF | None = None

    # ------------------------------------------------------------------ spaces
    def observation_space(self, agent: str) -> gym.spaces.Box:
        return self._observation_space

    def action_space(self, agent: str) -> gym.spaces.Discrete:
        return self._action_space

    # ------------------------------------------------------------------ episode
    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is not None:
            self.np_random, self.np_random_seed = seeding.np_random(seed)
        cfg, rng, n = self.config, self.np_random, self.n_robots
        layout_kwargs = {"robot_radius": cfg.robot.radius, **cfg.world.layout_kwargs}
        layout = make_layout(cfg.world.layout, rng, cfg.world.n_landmarks, **layout_kwargs)
        # Draws beside the world's stream, as the single-robot env's initial draw: the world stays the same.
        starts = team_starts(
            layout, n, cfg.team.start_spacing, cfg.team.start_spread, cfg.robot.radius,
            np.random.Generator(rng.bit_generator.jumped(2)),
        )  # fmt: skip
        # The wheel and velocity odometers at their defaults, as the single-robot env's ``World`` has them.
        self._world = world = TeamWorld(
            layout, starts, cfg.robot, cfg.sensor, cfg.odometry, WheelOdometryNoise(), cfg.dt, cfg.substeps
        )
        f = cfg.filter
        initial = starts.copy()
        if f.initial_draw:  # the single-robot env's ``initial_estimate``, one draw of 3 per robot
            draw = np.random.Generator(rng.bit_generator.jumped()).standard_normal((n, 3))
            initial = initial + math.sqrt(f.pose_prior) * draw
        self._ekf = ekf = TeamEKF(
            n, layout.n_landmarks, f, dt=cfg.dt, measurement_noise=cfg.sensor.cov, initial_poses=initial,
            min_range=max(cfg.sensor.min_range, 1e-3), wheel_base=world.wheel_noise.wheel_base,
        )  # fmt: skip
        self._mean, self._cov, self._observed = ekf.mean, ekf.cov, ekf.observed
        self._bounds = np.asarray(layout.bounds, dtype=np.float64)
        self._half_size = 0.5 * max(self._bounds[2] - self._bounds[0], self._bounds[3] - self._bounds[1])
        self._true_landmarks = np.ascontiguousarray(layout.landmarks, dtype=np.float64)
        self._memory = make_memory(self._bounds, cfg.observation.memory_resolution)
        self._last_seen = np.full(layout.n_landmarks, -1, dtype=np.int64)
        self._last_met = np.zeros((n, n), dtype=np.int64)
        self._t = 0
        self._steps = 0
        self._loop_closures = 0
        self._robot_loop_closures = 0
        self._collisions = np.zeros(n, dtype=np.int64)
        self._robot_contacts = np.zeros(n, dtype=np.int64)
        self._path_length = np.zeros(n)
        self._filter_failed = False
        self._single_pose = np.zeros(3 + 2 * layout.n_landmarks)
        self._single_cov = np.zeros((self._single_pose.size, self._single_pose.size))
        self._single_diagonal = np.arange(self._single_pose.size) * (self._single_pose.size + 1)
        self._scratch = np.zeros(self._layout.size, dtype=np.float32)

        readings = [world.sense(i, rng) for i in range(n)]
        met = self._read_robots(rng)
        for i, (ids, z) in enumerate(readings):
            ekf.correct(i, ids, z)
        self._correct_robots(met)
        self._stamp(readings, met)
        self._log_det = ekf.log_det
        for i in range(n):
            self._mark(i)
        self._worst_variance = self._worst_landmark_variance()
        self.agents = list(self.possible_agents)
        zeros = dict.fromkeys(REWARD_NAMES, 0.0)
        own = np.zeros((n, len(ROBOT_TERMS)))
        return self._observations(), self._infos(zeros, own, np.zeros(n, dtype=bool), 0)

    def step(self, actions: Mapping[str, Any]):
        if self._ekf is None or not self.agents:
            raise gym.error.ResetNeeded("call reset() before step() (the episode has ended)")
        missing = [a for a in self.agents if a not in actions]
        unknown = [a for a in actions if a not in self._index]
        if missing or unknown:
            raise ValueError(
                f"actions must name every live agent {self.agents}; missing {missing}, unknown {unknown}"
            )
        n = self.n_robots
        for i, agent in enumerate(self.possible_agents):
            self._interfaces[i].begin(actions[agent], self._mean[3 * i : 3 * i + 3])
        terms = dict.fromkeys(REWARD_NAMES, 0.0)
        own = np.zeros((n, len(ROBOT_TERMS)))
        collided = np.zeros(n, dtype=bool)
        reward, inner, terminated = 0.0, 0, False
        for _ in range(self._hold):
            commands = [
                self._interfaces[i].command(self._mean[3 * i : 3 * i + 3], lambda i=i: self._world.scan(i))
                for i in range(n)
            ]
            step = self._control_step(commands)
            inner += 1
            if step is None:  # the filter failed: the episode ends, the failed step pays nothing
                terminated = True
                break
            step_terms, step_own, step_collided = step
            for name, value in step_terms.items():
                terms[name] += value
            own += step_own
            collided |= step_collided
            reward += weigh(step_terms, self._weights)
            terminated = self._is_terminated(step_collided)
            if terminated:
                break
        self._steps += 1
        truncated = not terminated and self._steps >= self.config.max_episode_steps
        infos = self._infos(terms, own, collided, inner)
        observations = self._observations()
        agents = self.agents
        rewards = dict.fromkeys(agents, reward)
        terminations = dict.fromkeys(agents, terminated)
        truncations = dict.fromkeys(agents, truncated)
        if terminated or truncated:
            self.agents = []
        return observations, rewards, terminations, truncations, infos

    def _control_step(self, commands: list[tuple[float, float]]):
        """One control step of every robot: physics, odometry, readings, the joint filter, coverage and the
        reward terms. Returns (team terms, per-robot terms (N, 2), wall contacts (N,)), None if the filter
        failed."""
        world, rng, ekf, n = self._world, self.np_random, self._ekf, self.n_robots
        before = [world.pose_tuple(i) for i in range(n)]
        collided = world.step([(a0 * self._v_max, a1 * self._omega_max) for a0, a1 in commands]).copy()
        for i in range(n):
            x0, y0, _ = before[i]
            x1, y1, _ = world.pose_tuple(i)
            self._path_length[i] += math.hypot(x1 - x0, y1 - y0)
        self._collisions += collided
        self._robot_contacts += world.robot_collided
        model = self.config.filter.motion_model
        odometry, readings = [], []
        for i in range(n):  # each robot's odometer, then its sensor, in the single-robot env's order
            odometry.append(world.odometry(i, model, rng))
            readings.append(world.sense(i, rng))
        met = self._read_robots(rng)
        self._t += 1
        try:
            for i in range(n):
                ekf.predict(i, odometry[i].u, control_cov=odometry[i].cov)
            for i, (ids, z) in enumerate(readings):
                ekf.correct(i, ids, z)
            self._correct_robots(met)
            failed = not math.isfinite(ekf.log_det)
        except FilterDivergedError:
            failed = True
        if failed:
            self._filter_failed = True
            return None
        self._stamp(readings, met)
        covered = sum(self._mark(i) for i in range(n)) * self._cell_area
        before_log_det, self._log_det = self._log_det, ekf.log_det
        own = robot_terms(collided, self._cov, n)
        self._worst_variance = self._worst_landmark_variance()
        return team_terms(before_log_det, self._log_det, own, covered), own, collided

    def _read_robots(self, rng: np.random.Generator) -> list:
        if not self.config.team.robot_readings:
            return []
        return [self._world.read_robots(i, rng) for i in range(self.n_robots)]

    def _correct_robots(self, met: list) -> None:
        for i, (targets, z) in enumerate(met):
            if targets.shape[0]:
                self._ekf.correct_robots(i, targets, z)

    def _stamp(self, readings: list, met: list) -> None:
        """Count loop closures: a landmark re-read after ``loop_gap`` control steps unread by the team, and a
        pair of robots reading each other after ``loop_gap`` control steps apart (a robot-to-robot closure)."""
        t, gap = self._t, self.config.loop_gap
        for ids, _ in readings:
            if ids.shape[0]:
                last = self._last_seen[ids]
                self._loop_closures += int(np.count_nonzero((last >= 0) & (t - last >= gap)))
                self._last_seen[ids] = t
        for i, (targets, _) in enumerate(met):
            for j in targets.tolist():
                if t - self._last_met[i, j] >= gap and t - self._last_met[j, i] >= gap:
                    self._robot_loop_closures += 1
                self._last_met[i, j] = t

    def _mark(self, i: int) -> int:
        """Mark the shared coverage memory from robot i's pose estimate; returns the cells newly covered."""
        s = self.config.sensor
        return compiled.mark_coverage(
            self._memory, self._mean[3 * i : 3 * i + 3], self._bounds, self.config.observation.memory_resolution,
            s.max_range, s.fov,
        )  # fmt: skip

    def _worst_landmark_variance(self) -> float:
        """The largest eigenvalue of any landmark's 2 x 2 marginal covariance, m^2."""
        return kernels.worst_landmark_variance(self._cov, 3 * self.n_robots)

    def _is_terminated(self, collided: np.ndarray) -> bool:
        if self.config.terminate_on_collision and collided.any():
            return True
        return self._worst_variance < self._done_variance

    # ------------------------------------------------------------------ observation and info
    def _observations(self) -> dict[str, np.ndarray]:
        n, ekf = self.n_robots, self._ekf
        mean, cov = self._mean, self._cov
        k = 3 * n
        single, single_cov = self._single_pose, self._single_cov
        single[3:] = mean[k:]
        diagonal = np.diagonal(cov)
        flat_cov = single_cov.reshape(-1)
        flat_cov[self._single_diagonal[3:]] = diagonal[k:]
        _, log_det_poses = np.linalg.slogdet(ekf.pose_cov_given_map)
        log_det_map = self._log_det - log_det_poses
        identity = np.eye(3)
        time_left = max(0.0, 1.0 - self._steps / self.config.max_episode_steps)
        size = self._layout.size
        out = {}
        for i, agent in enumerate(self.possible_agents):
            single[:3] = mean[3 * i : 3 * i + 3]
            flat_cov[self._single_diagonal[:3]] = diagonal[3 * i : 3 * i + 3]
            observation = np.empty(self._observation_space.shape, dtype=np.float32)
            compiled.fill_observation(
                self._scratch, self._layout.offsets, self._constants, single, single_cov, self._observed,
                log_det_map, identity, self._world.scan(i), self._memory, self._bounds, time_left,
            )  # fmt: skip
            observation[:size] = self._scratch
            fill_teammates(observation[size:], i, mean, cov, n, self._half_size)
            out[agent] = observation
        return out

    def _infos(self, terms: dict, own: np.ndarray, collided: np.ndarray, inner: int) -> dict[str, dict]:
        mean, cov, observed = self._mean, self._cov, self._observed
        k = 3 * self.n_robots
        seen = int(np.count_nonzero(observed))
        rmse = kernels.map_rmse(mean, k, observed, self._true_landmarks)
        infos = {}
        for i, agent in enumerate(self.possible_agents):
            pose = mean[3 * i : 3 * i + 3].copy()
            pose_cov = cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3].copy()
            true_pose = self._world.pose(i)
            nees = kernels.pose_nees(true_pose, mean, cov, 3 * i)
            info = {
                "step": self._t,
                "true_pose": true_pose,
                "pose": pose,
                "pose_cov": pose_cov,
                "log_det": self._log_det,
                "reward_terms": dict(terms),
                "robot_terms": dict(zip(ROBOT_TERMS, own[i].tolist())),
                "landmarks_seen": seen,
                "collision": bool(collided[i]),
                "collisions": int(self._collisions[i]),
                "robot_contacts": int(self._robot_contacts[i]),
                "pose_nees": nees,
                "map_rmse": rmse,
                "loop_closures": self._loop_closures,
                "robot_loop_closures": self._robot_loop_closures,
                "path_length": float(self._path_length[i]),
                "filter_failed": self._filter_failed,
            }
            if inner:
                info["inner_steps"] = inner
            infos[agent] = info
        return infos

    # ------------------------------------------------------------------ access for baselines and evaluation
    @property
    def observation_layout(self) -> ObservationLayout:
        """Where each single-robot part lies in a robot's observation (the teammates follow them)."""
        return self._layout

    @property
    def filter(self) -> TeamEKF:
        """The team's filter (planners should read it, not change it)."""
        self._require_reset()
        return self._ekf

    @property
    def world(self) -> TeamWorld:
        """The simulator (privileged: true poses and walls, for baselines and evaluation only)."""
        self._require_reset()
        return self._world

    @property
    def true_landmarks(self) -> np.ndarray:
        """The true landmark positions (n, 2), m, read-only (privileged)."""
        self._require_reset()
        return _read_only(self._true_landmarks)

    @property
    def bounds(self) -> np.ndarray:
        """The world's extent (xmin, ymin, xmax, ymax), m, read-only."""
        self._require_reset()
        return _read_only(self._bounds)

    @property
    def coverage_memory(self) -> np.ndarray:
        """The team's shared coverage memory, read-only (``EKFSLAMEnv.coverage_memory``'s layout)."""
        self._require_reset()
        return _read_only(self._memory)

    @property
    def elapsed_steps(self) -> int:
        """Control steps since the last reset."""
        return self._t

    def _require_reset(self) -> None:
        if self._ekf is None:
            raise gym.error.ResetNeeded("call reset() first")

    def render(self) -> None:
        gym.logger.warn("the team env has no render mode yet")

    def close(self) -> None:
        pass


def _read_only(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.setflags(write=False)
    return view


def parallel_env(
    n_robots: int = 3, config=None, render_mode: str | None = None, **overrides: Any
) -> TeamSLAMEnv:
    """The team env as a PettingZoo ``ParallelEnv`` (``TeamSLAMEnv``'s docstring)."""
    return TeamSLAMEnv(n_robots, config, render_mode, **overrides)


def raw_env(n_robots: int = 3, config=None, render_mode: str | None = None, **overrides: Any):
    """The team env as an AEC env (PettingZoo's ``parallel_to_aec``), unwrapped."""
    return parallel_to_aec(parallel_env(n_robots, config, render_mode, **overrides))


def env(n_robots: int = 3, config=None, render_mode: str | None = None, **overrides: Any):
    """The team env as an AEC env with PettingZoo's usual wrappers (actions in bounds, call order enforced)."""
    aec = raw_env(n_robots, config, render_mode, **overrides)
    aec = wrappers.AssertOutOfBoundsWrapper(aec)
    return wrappers.OrderEnforcingWrapper(aec)
