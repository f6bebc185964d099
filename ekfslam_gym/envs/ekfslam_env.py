"""EKFSLAM-v0: a robot whose own EKF-SLAM belief is the observation and whose information gain is the reward."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numba import njit

from ..filter.ekf import EKFSLAM, FilterDivergedError
from ..sim.layouts import make_layout
from ..sim.world import World
from .config import EnvConfig
from .observation import CLIP, fill_observation, make_memory, mark_coverage, observation_layout

REWARD_TERMS = ("info_gain", "a_opt", "e_opt", "collision", "control_effort", "step_cost", "coverage")


@njit(cache=True)
def _step_metrics(mean, cov, observed, true_pose, true_landmarks, read_ids, last_seen, t, loop_gap):
    """Pose NEES, map RMSE of seen landmarks, new loop closures, largest landmark marginal variance.

    Also stamps ``last_seen`` for the landmarks read at step t. One compiled call instead of a dozen numpy ones.
    """
    e0 = true_pose[0] - mean[0]
    e1 = true_pose[1] - mean[1]
    e2 = (true_pose[2] - mean[2] + math.pi) % (2.0 * math.pi) - math.pi
    a, b, c = cov[0, 0], cov[0, 1], cov[0, 2]
    d, e, f = cov[1, 1], cov[1, 2], cov[2, 2]
    # e^T Sigma_xx^-1 e by cofactors of the symmetric 3x3 pose block.
    c00 = d * f - e * e
    c01 = c * e - b * f
    c02 = b * e - c * d
    c11 = a * f - c * c
    c12 = b * c - a * e
    c22 = a * d - b * b
    det = a * c00 + b * c01 + c * c02
    nees = (
        c00 * e0 * e0 + c11 * e1 * e1 + c22 * e2 * e2 + 2.0 * (c01 * e0 * e1 + c02 * e0 * e2 + c12 * e1 * e2)
    ) / det

    n = observed.shape[0]
    squared, seen = 0.0, 0
    worst = 0.0
    for j in range(n):
        lj = 3 + 2 * j
        if observed[j]:
            dx = mean[lj] - true_landmarks[j, 0]
            dy = mean[lj + 1] - true_landmarks[j, 1]
            squared += dx * dx + dy * dy
            seen += 1
            p, q, r = cov[lj, lj], cov[lj, lj + 1], cov[lj + 1, lj + 1]
            largest = 0.5 * (p + r) + math.sqrt(0.25 * (p - r) * (p - r) + q * q)
            worst = max(worst, largest)
        else:
            worst = np.inf
    rmse = math.sqrt(squared / seen) if seen else 0.0

    closures = 0
    for i in range(read_ids.shape[0]):
        j = read_ids[i]
        if last_seen[j] >= 0 and t - last_seen[j] >= loop_gap:
            closures += 1
        last_seen[j] = t
    return nees, rmse, closures, worst


class EKFSLAMEnv(gym.Env):
    """Active SLAM: drive a differential-drive robot so that its own EKF-SLAM map becomes certain.

    ## Description
    A pymunk-simulated differential-drive robot moves among walls and point landmarks (a layout generated anew
    at every reset: an open ``arena``, ``rooms`` with doorways, or a corridor ``loop``). A range-bearing sensor
    reads the landmarks within range and field of view that no wall hides, with Gaussian noise and known
    identities; noisy odometry reports the robot's motion. An EKF-SLAM inside the env fuses both. The agent
    sees the filter's belief, never the true map, and is paid for the information it gains.

    ## Action Space
    ``Box(-1, 1, (2,), float32)``: (forward speed, turn rate) as fractions of ``robot.v_max`` (m/s) and
    ``robot.omega_max`` (rad/s). Values outside [-1, 1] are clipped; NaN, inf or a wrong shape raise
    ``ValueError`` and change nothing.

    ## Observation Space
    ``Box(-5, 5, (D,), float32)`` with D = 4 + 3 + 4k + 3 + B + G^2 + C^2 (164 by default: k = 8 landmark
    slots, B = 16 scan beams, a 9 x 9 robot-centred window of the coverage memory and a coarse 5 x 5 one), or with ``observation.kind = "dict"`` a ``Dict`` of the same
    parts: ``pose``, ``pose_cov``, ``landmarks``, ``globals``, ``scan``, ``coverage``, ``coverage_coarse`` (see
    ``ekfslam_gym.envs.observation`` for every entry and its normalisation).

    ## Rewards
    The sum of the terms in ``info["reward_terms"]`` (those with a non-zero weight in ``reward``):
    ``info_gain`` = log det Sigma_{t-1} - log det Sigma_t of the filter's full, fixed-size covariance (weight 1
    by default), so an episode's information-gain terms sum to log det Sigma_0 - log det Sigma_T. Unseen
    landmarks are carried at the bounded prior ``filter.landmark_prior`` (100 m^2), so discovering one pays
    ln(landmark_prior^2 / det(Gz Q Gz^T)) = ln(landmark_prior^2 / (r^2 range_std^2 bearing_std^2)), about
    23.3 - 2 ln r nats for a landmark first read at r m with the default sensor; the pose starts at
    ``filter.pose_prior``.
    ``collision`` = -1 per step in contact with a wall. Optional: ``a_opt``, ``e_opt`` (drops of ln trace and
    ln lambda_max of Sigma), ``control_effort`` (-w |a|^2), ``step_cost`` (-w per step), ``coverage`` (w per m^2
    the sensor looks at for the first time: an exploration shaping for training).

    Standing still earns little: every prediction adds odometry noise (the noise floor), a negative term, and
    re-observing the same landmarks pays ever less (the information about them grows like ln t). Because the
    terms telescope, the most any policy can collect is log det Sigma_0 - log det Sigma_T: it is bounded by
    what remains unknown, and a landmark seen once already has paid most of what it ever will. Exploring pays
    the discovery terms; closing a loop pays the pose and map correlations it removes.

    ## Starting State
    The robot at the layout's start pose, known to the filter (pose prior ``filter.pose_prior``); ``reset``
    takes a first reading and corrects, and Sigma_0 is the belief after that (``info["log_det"]``).

    ## Episode End
    Terminated: on a wall contact if ``terminate_on_collision``; when every landmark's marginal standard
    deviation is below ``done_std`` m; when the filter fails numerically (``info["filter_failed"]``, never an
    exception). Truncated: after ``max_episode_steps`` steps (from the config; the env truncates itself).

    ## Arguments
    ``gymnasium.make("EKFSLAM-v0", config=None, render_mode=None, **overrides)``: ``config`` is an
    ``EnvConfig``, a path to a YAML file (see ``configs/env/``) or a mapping of sections; ``overrides`` are
    sections given as keyword arguments, e.g. ``world={"n_landmarks": 50}, reward={"collision": 2.0}``.
    A bad value raises ``ValueError`` naming the field.

    ## Registered Configurations
    - ``EKFSLAM-v0``: 20 x 20 m arena, 30 landmarks, 500 steps of 0.1 s.
    - ``EKFSLAM-Loop-v0``: a corridor ring (the loop layout), 30 landmarks, 800 steps: closing the loop pays.
    - ``EKFSLAM-Large-v0``: 40 x 40 m rooms, 120 landmarks, 1000 steps.
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 10}

    def __init__(
        self,
        config: EnvConfig | str | Path | Mapping[str, Any] | None = None,
        render_mode: str | None = None,
        **overrides: Any,
    ) -> None:
        if isinstance(config, EnvConfig):
            config = EnvConfig.from_overrides(config, **overrides)
        elif isinstance(config, (str, Path)):
            config = EnvConfig.from_yaml(config, **overrides)
        elif isinstance(config, Mapping):
            config = EnvConfig.from_overrides(EnvConfig.from_overrides(**config), **overrides)
        elif config is None:
            config = EnvConfig.from_overrides(**overrides)
        else:
            raise TypeError(
                f"config must be an EnvConfig, a YAML path or a mapping, got {type(config).__name__}"
            )
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}"
            )
        self.config: EnvConfig = config
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": int(round(1.0 / config.dt))}

        obs_cfg = config.observation
        self._layout_slices = observation_layout(
            obs_cfg.k_nearest, config.sensor.n_beams, obs_cfg.grid, obs_cfg.coarse_grid
        )
        size = sum(s.stop - s.start for s in self._layout_slices.values())
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        flat = spaces.Box(-CLIP, CLIP, shape=(size,), dtype=np.float32)
        if obs_cfg.kind == "box":
            self.observation_space = flat
        else:
            self.observation_space = spaces.Dict(
                {name: spaces.Box(-CLIP, CLIP, shape=(s.stop - s.start,), dtype=np.float32)
                 for name, s in self._layout_slices.items()}
            )  # fmt: skip
        self._obs = np.zeros(size, dtype=np.float32)
        self._weights = np.array([getattr(config.reward, name) for name in REWARD_TERMS])
        self._world: World | None = None
        self._ekf: EKFSLAM | None = None
        self._renderer = None

    # ------------------------------------------------------------------ episode
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        cfg = self.config
        rng = self.np_random
        layout_kwargs = {"robot_radius": cfg.robot.radius, **cfg.world.layout_kwargs}
        layout = make_layout(cfg.world.layout, rng, cfg.world.n_landmarks, **layout_kwargs)
        self._world = World(layout, cfg.robot, cfg.sensor, cfg.odometry, None, cfg.dt, cfg.substeps)
        f = cfg.filter
        self._ekf = EKFSLAM(
            layout.n_landmarks, motion_model=f.motion_model, dt=cfg.dt, measurement_noise=cfg.sensor.cov,
            landmark_prior=f.landmark_prior, pose_prior=f.pose_prior, init_mode=f.init_mode, update=f.update,
            initial_pose=layout.start, min_range=max(cfg.sensor.min_range, 1e-3), resync_every=f.resync_every,
        )  # fmt: skip
        self._bounds = np.asarray(layout.bounds, dtype=np.float64)
        self._centre = np.array(
            [0.5 * (self._bounds[0] + self._bounds[2]), 0.5 * (self._bounds[1] + self._bounds[3])]
        )
        self._half_size = 0.5 * max(self._bounds[2] - self._bounds[0], self._bounds[3] - self._bounds[1])
        self._true_landmarks = np.ascontiguousarray(layout.landmarks, dtype=np.float64)
        self._memory = make_memory(self._bounds, cfg.observation.memory_resolution)
        self._last_seen = np.full(layout.n_landmarks, -1, dtype=np.int64)
        self._t = 0
        self._loop_closures = 0
        self._collisions = 0
        self._path_length = 0.0
        self._filter_failed = False
        self._trail_true: list[tuple[float, float]] = []
        self._trail_est: list[tuple[float, float]] = []

        readings = self._world.sense(rng)
        self._ekf.correct(readings.ids, readings.z)
        self._log_det = self._ekf.log_det
        self._trace = float(np.trace(self._ekf._cov)) if self._weights[1] else 0.0
        self._lambda_max = self._largest_eigenvalue() if self._weights[2] else 0.0
        self._last_readings = readings
        self._odometry = np.zeros(3 if f.motion_model == "odometry" else 2)
        self._odometry_cov = np.zeros((self._odometry.size, self._odometry.size))
        self._mark_and_trail()
        nees, rmse, _, _ = self._metrics(readings.ids)
        info = self._info({"info_gain": 0.0}, False, nees, rmse)
        if self.render_mode == "human":
            self.render()
        return self._observation(), info

    def step(self, action):
        if self._ekf is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        a = np.asarray(action, dtype=np.float64)
        if a.shape != (2,):
            raise ValueError(f"action must have shape (2,), got {a.shape}")
        a0, a1 = float(a[0]), float(a[1])
        if not (math.isfinite(a0) and math.isfinite(a1)):
            raise ValueError(f"action must be finite, got {action!r}")
        a0 = min(max(a0, -1.0), 1.0)
        a1 = min(max(a1, -1.0), 1.0)
        cfg = self.config
        world, ekf, rng = self._world, self._ekf, self.np_random

        prev_pose = world._pose
        collided = world.step(a0 * cfg.robot.v_max, a1 * cfg.robot.omega_max)
        self._path_length += math.hypot(world._pose[0] - prev_pose[0], world._pose[1] - prev_pose[1])
        self._collisions += collided
        odometry = (
            world.odometry(rng) if self._ekf.motion_model == "odometry" else world.velocity_odometry(rng)
        )
        readings = world.sense(rng)
        self._odometry, self._odometry_cov, self._last_readings = odometry.u, odometry.cov, readings
        self._t += 1

        terms: dict[str, float] = {}
        try:
            ekf.predict(odometry.u, control_cov=odometry.cov)
            ekf.correct(readings.ids, readings.z)
            failed = not math.isfinite(ekf.log_det)
        except FilterDivergedError:
            failed = True
        if failed:
            self._filter_failed = True
            terms["info_gain"] = 0.0
            info = self._info(terms, collided, math.nan, math.nan)
            return self._obs_out(), 0.0, True, False, info

        w = self._weights
        log_det = ekf.log_det
        if w[0]:
            terms["info_gain"] = w[0] * (self._log_det - log_det)
        self._log_det = log_det
        if w[1]:
            trace = float(np.trace(ekf._cov))
            terms["a_opt"] = w[1] * (math.log(self._trace) - math.log(trace))
            self._trace = trace
        if w[2]:
            largest = self._largest_eigenvalue()
            terms["e_opt"] = w[2] * (math.log(self._lambda_max) - math.log(largest))
            self._lambda_max = largest
        if w[3]:
            terms["collision"] = -w[3] * collided
        if w[4]:
            terms["control_effort"] = -w[4] * (a0 * a0 + a1 * a1)
        if w[5]:
            terms["step_cost"] = -w[5]
        newly_covered = self._mark_and_trail()
        if w[6]:
            terms["coverage"] = w[6] * newly_covered * self.config.observation.memory_resolution**2
        reward = sum(terms.values())

        nees, rmse, closures, worst = self._metrics(readings.ids)
        self._loop_closures += closures
        terminated = (collided and cfg.terminate_on_collision) or (
            cfg.done_std > 0 and worst < cfg.done_std**2
        )
        truncated = self._t >= cfg.max_episode_steps and not terminated
        info = self._info(terms, collided, nees, rmse)
        if self.render_mode == "human":
            self.render()
        return self._observation(), reward, bool(terminated), bool(truncated), info

    # ------------------------------------------------------------------ pieces
    def _largest_eigenvalue(self) -> float:
        return float(np.linalg.eigvalsh(self._ekf._cov)[-1])

    def _metrics(self, read_ids):
        ekf = self._ekf
        return _step_metrics(
            ekf._mean, ekf._cov, ekf._observed, np.asarray(self._world._pose), self._true_landmarks, read_ids,
            self._last_seen, self._t, self.config.loop_gap,
        )  # fmt: skip

    def _mark_and_trail(self) -> int:
        """Update the coverage memory (and the trails when rendering); returns the cells newly covered."""
        sensor = self.config.sensor
        resolution = self.config.observation.memory_resolution
        new = mark_coverage(
            self._memory, self._ekf._mean, self._bounds, resolution, sensor.max_range, sensor.fov
        )
        if self.render_mode is not None:
            pose = self._world._pose
            self._trail_true.append((pose[0], pose[1]))
            self._trail_est.append((float(self._ekf._mean[0]), float(self._ekf._mean[1])))
        return new

    def _observation(self):
        ekf, cfg = self._ekf, self.config
        time_left = max(0.0, 1.0 - self._t / cfg.max_episode_steps)
        obs = cfg.observation
        fill_observation(
            self._obs, ekf._mean, ekf._cov, ekf._observed, self._log_det, ekf._P, self._world.scan(), self._memory,
            self._bounds, obs.memory_resolution, obs.grid, obs.grid_extent, obs.coarse_grid, obs.coarse_extent,
            self._centre, self._half_size,
            cfg.sensor.max_range, cfg.sensor.scan_max_range, time_left, obs.k_nearest,
        )  # fmt: skip
        return self._obs_out()

    def _obs_out(self):
        if self.config.observation.kind == "box":
            return self._obs.copy()
        return {name: self._obs[s].copy() for name, s in self._layout_slices.items()}

    def _info(self, terms, collided, nees, rmse) -> dict[str, Any]:
        ekf = self._ekf
        return {
            "step": self._t,
            "true_pose": self._world.pose,
            "pose": ekf._mean[:3].copy(),
            "pose_cov": ekf._cov[:3, :3].copy(),
            "log_det": self._log_det,
            "reward_terms": terms,
            "landmarks_seen": int(ekf._observed.sum()),
            "collision": bool(collided),
            "collisions": self._collisions,
            "pose_nees": nees,
            "map_rmse": rmse,
            "loop_closures": self._loop_closures,
            "path_length": self._path_length,
            "odometry": self._odometry.copy(),
            "odometry_cov": self._odometry_cov.copy(),
            # A (ids, z) named tuple, not arrays: the number of readings varies, and vector envs stack arrays.
            "readings": self._last_readings,
            "filter_failed": self._filter_failed,
        }

    # ------------------------------------------------------------------ access for agents and evaluation
    @property
    def filter(self) -> EKFSLAM:
        """The env's filter (read-only views of its state; planners should work on ``filter.copy()``)."""
        if self._ekf is None:
            raise gym.error.ResetNeeded("call reset() first")
        return self._ekf

    @property
    def world(self) -> World:
        """The simulator (privileged: true poses and walls, for baselines and evaluation only)."""
        if self._world is None:
            raise gym.error.ResetNeeded("call reset() first")
        return self._world

    @property
    def true_landmarks(self) -> np.ndarray:
        return self._true_landmarks

    # ------------------------------------------------------------------ rendering
    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' or 'human'")
            return None
        if self._ekf is None:
            raise gym.error.ResetNeeded("call reset() before render()")
        from .render import Renderer, Scene

        if self._renderer is None:
            self._renderer = Renderer(self.render_mode, fps=self.metadata["render_fps"])
        ekf, world, cfg = self._ekf, self._world, self.config
        scene = Scene(
            bounds=self._bounds,
            walls=np.asarray(world.layout.walls),
            wall_radius=float(world.layout.wall_radius),
            robot_radius=cfg.robot.radius,
            landmarks_true=self._true_landmarks,
            landmarks_est=ekf._mean[3:].reshape(-1, 2).copy(),
            landmark_covs=ekf.landmark_covs(),
            seen=ekf._observed.copy(),
            pose_true=world.pose,
            pose_est=ekf._mean[:3].copy(),
            pose_cov=ekf._cov[:3, :3].copy(),
            read_ids=np.asarray(self._last_readings.ids),
            trail_true=np.array(self._trail_true).reshape(-1, 2),
            trail_est=np.array(self._trail_est).reshape(-1, 2),
            max_range=cfg.sensor.max_range,
            fov=cfg.sensor.fov,
            text=f"t={self._t}  log det={self._log_det:.1f}  seen={int(ekf._observed.sum())}/{ekf.n_landmarks}",
        )
        return self._renderer.render(scene)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
