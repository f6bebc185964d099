"""EKFSLAM-v0: a robot whose own EKF-SLAM belief is the observation and whose information gain is the reward."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np

from .. import compiled
from ..filter.ekf import EKFSLAM, FilterDivergedError
from ..sim.layouts import make_layout
from ..sim.sensor import Readings
from ..sim.world import World
from . import rewards
from .actions import make_interface
from .config import EnvConfig, build_config
from .observation import ObservationLayout, make_memory, observation_constants, observation_space
from .rewards import StepContext, Telescoped

ODOMETERS = {"odometry": "odometry", "wheels": "wheel_odometry", "velocity": "velocity_odometry"}


def initial_estimate(start: np.ndarray, pose_prior: float, rng: np.random.Generator) -> np.ndarray:
    """The filter's initial pose: a draw from its prior N(start, pose_prior I) around the true ``start``.

    Starting exactly at the truth, the filter would count the prior's variance with no error to match it: at
    1e-10 that is as much as a step's sideways slip noise, and the first steps' pose NEES fell to 2.4 of 3.
    The draw comes from a stream jumped off ``rng``'s, which it leaves where it was, so the world (layout,
    readings, odometry) is the same as without it.
    """
    draw = np.random.Generator(rng.bit_generator.jumped()).standard_normal(3)
    pose = np.asarray(start, dtype=np.float64) + math.sqrt(pose_prior) * draw
    return pose


class StepMetrics(NamedTuple):
    """``compiled.step_metrics`` of one control step (or reset), by name."""

    nees: float  # the pose's NEES (3 dof)
    rmse: float  # m, the mapped landmarks' RMS position error (NaN before the first)
    loop_closures: int  # re-observations of landmarks unseen for loop_gap control steps, in this step
    worst_variance: float  # m^2, the largest landmark marginal variance (for done_std)
    landmarks_seen: int
    truth_gain: float  # m^2
    belief_gain: float  # m^2


class ControlStep(NamedTuple):
    """What one control step did (``_control_step``); an env step runs one or several."""

    terms: dict[str, float]  # every reward term, unweighted
    reward: float  # the weighted sum of ``terms``
    metrics: StepMetrics
    collided: bool
    terminated: bool
    failed: bool  # the filter failed numerically (terminated, reward 0)


class EKFSLAMEnv(gym.Env):
    """Active SLAM: drive a differential-drive robot so that its own EKF-SLAM map becomes certain.

    ## Description
    A pymunk-simulated robot moves among walls and point landmarks (a layout generated anew at every reset: an
    open ``arena``, ``rooms`` with doorways, or a corridor ``loop``). A range-bearing sensor reads the visible
    landmarks with Gaussian noise, and noisy odometry reports the motion; an EKF-SLAM inside the env fuses both
    (Thrun, Burgard & Fox, *Probabilistic Robotics*, ch. 10), told each reading's landmark by default or
    associating them itself (``filter.association``, with ``sensor.detection_prob`` and ``clutter_rate``). The
    agent sees the filter's belief, never the true map, and is paid for the information it gains.
    ``docs/belief-and-truth.md`` shows how to read the belief and the truth, and every ``info`` key.

    ## Action Space
    ``action.kind`` (``ekfslam_gym.envs.actions``): ``velocity`` (default), ``Box(-1, 1, (2,), float32)``,
    (forward speed, turn rate) as fractions of ``robot.v_max`` and ``robot.omega_max``, one control step of
    ``dt`` s; ``primitives``, ``Discrete(9)``, one of ``PRIMITIVES`` held for ``action.hold`` control steps
    (default 10; ``action.guard`` stops it short of walls); ``waypoint``, ``Box(-1, 1, (2,))``, a goal relative
    to the pose estimate, driven for at most ``hold`` (default 10) control steps. Out-of-range values are
    clipped; NaN, inf or a wrong shape raise ``ValueError`` and change nothing.

    ## Observation Space
    ``Box(-5, 5, (D,), float32)``, D = 164 by default, or with ``observation.kind = "dict"`` a ``Dict`` of the same
    parts (``pose``, ``pose_cov``, ``landmarks``, ``globals``, ``scan``, ``coverage``, ``coverage_coarse``),
    optionally with a ``belief_image`` for a CNN and the ``last_action``; all from the belief and the wall scan.
    *The observation vector* below describes every entry; ``env.observation_layout`` says where each lies.

    ## Rewards
    The sum over ``REWARD_TERMS`` (*Reward terms* below) of each term times its weight in ``reward``; the
    default is the information gain, log det Sigma_{t-1} - log det Sigma_t of the filter's full covariance, less
    1 per control step in contact with a wall. ``info["reward_terms"]`` reports every term unweighted. The
    information gain telescopes to log det Sigma_0 - log det Sigma_T, so no policy can collect more than what
    remains unknown: a landmark first read at r m pays about 23.3 - 2 ln r nats (unseen ones are carried at
    ``filter.landmark_prior``), re-observing pays ever less, and closing a loop pays the correlations it removes.
    Every prediction adds odometry noise, so standing still costs a little; the first control step costs about
    8 to 20 nats, even standing still, because the pose starts known to ``filter.pose_prior`` (1e-10) and the
    first odometry noise is orders of magnitude larger (``docs/belief-and-truth.md``, *The first step's
    reward*). A macro step's reward is the sum of its control steps'.

    ## Starting State
    The robot at the layout's start pose, known to the filter (``filter.pose_prior``; with
    ``filter.initial_draw`` its estimate is a draw from that prior, a belief calibrated from the first step);
    ``reset`` takes a first reading and corrects, and Sigma_0 is the belief after that (``info["log_det"]``).

    ## Episode End
    Terminated: on a wall contact if ``terminate_on_collision``; when every landmark's marginal standard
    deviation is below ``done_std`` m; when the filter fails numerically (``info["filter_failed"]``, never an
    exception). Truncated after the step limit N in env steps, one number for ``gym.make``'s TimeLimit, the
    env's own truncation and the time-left entry (``ekfslam_gym.envs.horizon``): the registered id's limit
    (500, 800, 1000 control steps), divided by ``action.hold`` for macro actions so that an episode lasts the
    same simulated time, unless ``gym.make(id, max_episode_steps=N)`` or the config's ``max_episode_steps``
    gives N.

    ## Arguments
    ``gymnasium.make("EKFSLAM-v0", config=None, render_mode=None, **overrides)``: ``config`` is a mapping of
    sections or a path to a YAML file of them (``configs/env/``), merged onto the id's preset
    (``gym.make("EKFSLAM-Large-v0", config={"world": {"n_landmarks": 40}})`` keeps the Large rooms and 1000
    steps), or a complete ``EnvConfig``, used as it is; ``preset=None`` starts from the defaults instead of the
    id's preset, and ``EKFSLAMEnv(preset="EKFSLAM-Large-v0")`` builds an id's configuration without
    ``gym.make``. ``overrides`` are sections applied on top, e.g. ``world={"n_landmarks": 50},
    reward={"collision": 2.0}, filter={"motion_model": "odometry"}`` (``ekfslam_gym.filter.FilterSettings``). A
    bad value raises ``ValueError`` naming the field. ``render_mode``: ``rgb_array`` or ``human``;
    ``render_options``: ``{"legend": False}`` drops the frame's legend, ``{"landmark_ellipse_scale": 5}`` draws
    the landmark ellipses five times larger (``ekfslam_gym.envs.render.RenderOptions``).

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
        *,
        preset: str | None = None,
        render_options: Mapping[str, Any] | None = None,
        **overrides: Any,
    ) -> None:
        config = build_config(config, preset, overrides)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}"
            )
        self.config: EnvConfig = config
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": int(round(1.0 / config.dt))}

        self._layout = ObservationLayout.from_config(config.observation, config.sensor)
        self._interface = make_interface(config)
        self.action_space = self._interface.space
        self._hold = config.action.hold
        # Macro actions (primitives, waypoint, a held velocity) report their control steps in info.
        self._macro = config.action.kind != "velocity" or self._hold > 1
        self.observation_space = observation_space(self._layout, config.observation, self.action_space)
        self._obs = np.zeros(self._layout.size, dtype=np.float32)
        self._flat = config.observation.kind == "box"
        # The belief image (observation.belief_image): its buffer, filled with the observation; nothing of it
        # runs when off.
        self._belief_image = config.observation.belief_image
        if self._belief_image:
            self._image = np.zeros(self.observation_space["belief_image"].shape, dtype=np.float32)
        # The last executed action (observation.last_action), one-hot for primitives; None when off.
        self._last_action = (
            np.zeros(self.observation_space["last_action"].shape, dtype=np.float32)
            if config.observation.last_action
            else None
        )
        self._constants = observation_constants(config.observation, config.sensor)
        self._weights = rewards.nonzero_weights(config.reward)
        self._cell_area = config.observation.memory_resolution**2
        # Constants of the step, read once here rather than through the config at every step.
        self._v_max, self._omega_max = config.robot.v_max, config.robot.omega_max
        # mark_coverage's settings: memory resolution (m), the sensor's reach (m) and field of view (rad).
        resolution, sensor = config.observation.memory_resolution, config.sensor
        self._coverage_settings = (resolution, sensor.max_range, sensor.fov)
        self._loop_gap = config.loop_gap
        self._done_variance = config.done_std**2 if config.done_std > 0 else -math.inf
        self._max_steps = config.max_episode_steps
        # Readings go through ``_correct_unknown`` when the filter associates them itself, or to drop clutter.
        self._unknown = config.filter.association != "known" or config.sensor.clutter_rate > 0
        self._world: World | None = None
        self._ekf: EKFSLAM | None = None
        self._belief: tuple[np.ndarray, ...] | None = None
        self._t = 0
        self._steps = 0
        self._renderer = None
        from .render import RenderOptions  # no pygame: the options are checked here, the picture drawn later

        self.render_options = RenderOptions.build(dict(render_options) if render_options else None)

    def set_max_episode_steps(self, steps: int) -> None:
        """Make ``steps`` the episode's step limit: truncation and the observation's time left follow it.

        ``gym.make`` calls this (through ``HorizonSync``) when given ``max_episode_steps``, so the TimeLimit
        wrapper and the env agree; ``config.max_episode_steps`` reports the limit in force.
        """
        self.config = EnvConfig.from_overrides(self.config, max_episode_steps=steps)
        self._max_steps = self.config.max_episode_steps

    # ------------------------------------------------------------------ episode
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        cfg = self.config
        rng = self.np_random
        layout_kwargs = {"robot_radius": cfg.robot.radius, **cfg.world.layout_kwargs}
        layout = make_layout(cfg.world.layout, rng, cfg.world.n_landmarks, **layout_kwargs)
        self._world = World(layout, cfg.robot, cfg.sensor, cfg.odometry, None, cfg.dt, cfg.substeps)
        f = cfg.filter
        self._ekf = ekf = EKFSLAM(
            layout.n_landmarks, f.settings, dt=cfg.dt, measurement_noise=cfg.sensor.cov,
            initial_pose=initial_estimate(layout.start, f.pose_prior, rng) if f.initial_draw else layout.start,
            min_range=max(cfg.sensor.min_range, 1e-3), wheel_base=self._world.wheel_noise.wheel_base,
        )  # fmt: skip
        # The world's odometer for the filter's motion model, chosen once per episode rather than every step.
        self._read_odometry = getattr(self._world, ODOMETERS[f.motion_model])
        self._wheels = f.motion_model == "wheels"  # then one call reads the odometry and the landmarks
        self._bounds = np.asarray(layout.bounds, dtype=np.float64)
        self._true_landmarks = np.ascontiguousarray(layout.landmarks, dtype=np.float64)
        self._memory = make_memory(self._bounds, cfg.observation.memory_resolution)
        if self._belief_image:
            self._walls = make_memory(self._bounds, cfg.observation.memory_resolution)
            self._beam_angles = np.ascontiguousarray(self._world.sensor.beam_angles, dtype=np.float64)
        self._last_seen = np.full(layout.n_landmarks, -1, dtype=np.int64)
        known = f.association == "known"
        self._slot_truth = np.arange(layout.n_landmarks) if known else np.full(layout.n_landmarks, -1)
        # The true position each slot holds and which initialised slots hold one (unknown association only).
        self._slot_landmarks = self._true_landmarks.copy() if known else np.zeros_like(self._true_landmarks)
        self._slot_valid = np.zeros(layout.n_landmarks, dtype=bool)
        # Each slot's squared position error at the last step (-1: not seen then), for the truth gain, and
        # the trace of its marginal position covariance then, for the belief gain.
        self._errors = np.full(layout.n_landmarks, -1.0)
        self._traces = np.zeros(layout.n_landmarks)
        self._false_associations = 0
        self._missed_associations = 0
        self._t = 0
        self._steps = 0
        self._loop_closures = 0
        self._collisions = 0
        self._path_length = 0.0
        self._filter_failed = False
        self._collided = False
        if self._last_action is not None:
            self._last_action[:] = 0.0
        self._trail_true: list[tuple[float, float]] = []
        self._trail_est: list[tuple[float, float]] = []

        self._odometry = np.zeros(2 if f.motion_model == "velocity" else 3)
        self._odometry_cov = np.zeros((self._odometry.size, self._odometry.size))
        read = self._filter_update(None, self._world.sense(rng))
        self._take_views()
        self._telescoped = Telescoped(ekf.log_det)
        self._mark_and_trail()
        if self._belief_image:
            self._mark_walls()
        metrics = self._step_metrics(read, self._world.pose_tuple)
        self._worst_variance = metrics.worst_variance
        info = self._info(dict.fromkeys(rewards.REWARD_NAMES, 0.0), metrics, 0.0, 0.0, False)
        if self.render_mode == "human":
            self.render()
        return self._observation(), info

    def step(self, action):
        """One env step: the action's control steps (one for ``velocity``, up to ``action.hold`` for a macro
        action), each physics, odometry, readings, filter, metrics and reward terms; then one observation and
        one info. A macro step sums its control steps' rewards, terms and gains, and ends early when its
        controller is done (a waypoint reached or blocked) or the episode terminates."""
        if self._ekf is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        interface = self._interface
        pose = self._pose_estimate
        interface.begin(action, pose)
        if self._last_action is not None:
            interface.encode(self._last_action)
        commands: list[tuple[float, float]] = []
        steps: list[ControlStep] = []
        for _ in range(self._hold):
            command = interface.command(pose, self._world.scan)
            if command is None:
                if commands:
                    break
                command = (0.0, 0.0)  # a goal reached at once still takes one control step, standing
            commands.append(command)
            control_step = self._control_step(*command)
            steps.append(control_step)
            if control_step.terminated:
                break
        self._steps += 1

        last = steps[-1]
        terms, reward, truth_gain, belief_gain, collided = _summed(steps)
        terminated = last.terminated
        truncated = not terminated and self._is_truncated()
        info = self._info(terms, last.metrics, truth_gain, belief_gain, collided)
        if self._macro:
            info["inner_steps"] = len(steps)
            info["inner_actions"] = np.array(commands, dtype=np.float64)
        if last.failed:
            return self._observation_out(), reward, True, False, info  # the last observation the filter made
        if self.render_mode == "human":
            self.render()
        return self._observation(), reward, terminated, truncated, info

    def _control_step(self, a0: float, a1: float) -> ControlStep:
        """One control step of ``dt`` with the normalised command (a0, a1), already clipped: physics, odometry,
        readings, filter, metrics and reward terms. The caller builds the observation and info."""
        world, rng = self._world, self.np_random
        x0, y0, _ = world.pose_tuple
        collided = world.step(a0 * self._v_max, a1 * self._omega_max)
        true_pose = world.pose_tuple
        x1, y1, _ = true_pose
        self._path_length += math.hypot(x1 - x0, y1 - y0)
        self._collisions += collided
        self._collided = collided
        if self._wheels:
            odometry, readings = world.wheel_odometry_and_readings(rng)
        else:
            odometry = self._read_odometry(rng)
            readings = world.sense(rng)
        self._odometry, self._odometry_cov = odometry.u, odometry.cov
        self._t += 1
        try:
            read = self._filter_update(odometry, readings)
            log_det = self._ekf.log_det
            failed = not math.isfinite(log_det)
        except FilterDivergedError:
            failed = True
        if failed:
            self._filter_failed = True
            seen = int(np.count_nonzero(self._belief[2]))
            metrics = StepMetrics(math.nan, math.nan, 0, self._worst_variance, seen, 0.0, 0.0)
            return ControlStep(dict.fromkeys(rewards.REWARD_NAMES, 0.0), 0.0, metrics, collided, True, True)

        covered = self._mark_and_trail() * self._cell_area
        if self._belief_image:
            self._mark_walls()
        metrics = self._step_metrics(read, true_pose)
        self._loop_closures += metrics.loop_closures
        self._worst_variance = metrics.worst_variance
        before, self._telescoped = self._telescoped, Telescoped(log_det)
        terms = rewards.evaluate(StepContext(before, self._telescoped, self._pose_cov, collided, covered))
        reward = rewards.weigh(terms, self._weights)
        return ControlStep(terms, reward, metrics, collided, self._is_terminated(), False)

    def _filter_update(self, odometry, readings: Readings) -> np.ndarray:
        """Predict with ``odometry`` (None at reset, when nothing has moved) and correct with ``readings``;
        returns the slots read. The readings go through ``_correct_unknown`` when the filter associates them
        itself or clutter must be dropped; else the filter takes them with their ids, in one call with the
        prediction."""
        ekf = self._ekf
        self._last_readings = readings
        if self._unknown:
            if odometry is not None:
                ekf.predict(odometry.u, control_cov=odometry.cov)
            return self._correct_unknown(readings)
        if odometry is None:
            ekf.correct(readings.ids, readings.z)
        else:
            ekf.update(odometry.u, odometry.cov, readings.ids, readings.z)
        return readings.ids

    def _correct_unknown(self, readings: Readings) -> np.ndarray:
        """Correct with the step's readings without telling the filter their ids (``filter.association``), or,
        with known association, without the clutter. Counts false and missed associations against the true
        ids and keeps the slot -> true landmark map (``association_truth``); keeps what the filter used as
        the step's readings (ids their slots) and returns the slots read."""
        ekf, f = self._ekf, self.config.filter
        ids, z = readings
        if f.association == "known":
            keep = ids >= 0
            ids, z = ids[keep], z[keep]
            ekf.correct(ids, z)
            self._slot_valid[:] = ekf.observed
            self._last_readings = Readings(ids, z)
            return ids
        if z.shape[0] > 1:
            # Bearing order: the sensor's id order (clutter last) would tell the filter which readings are false.
            order = np.argsort(z[:, 1], kind="stable")
            z, ids = z[order], ids[order]
        slots, new, forgotten, _ = ekf.correct_unknown(z, f.association_settings)
        false, missed, read, read_z = compiled.tally_associations(
            ids, z, slots, new, forgotten, ekf.observed, self._slot_truth, self._true_landmarks,
            self._slot_landmarks, self._slot_valid,
        )  # fmt: skip
        self._false_associations += false
        self._missed_associations += missed
        self._last_readings = Readings(read, read_z)
        return read

    def _step_metrics(self, read: np.ndarray, true_pose: tuple[float, float, float]) -> StepMetrics:
        """``compiled.step_metrics`` of the step, ``read`` the slots the filter used, ``true_pose`` the world's
        ``pose_tuple`` after it. With known association slot j is landmark j; otherwise each slot is scored
        against the true landmark it holds (slots of clutter and free slots count as unseen, so the done_std end
        waits for every slot to hold one)."""
        mean, cov, observed, _ = self._belief
        if self._unknown:
            observed, landmarks = self._slot_valid, self._slot_landmarks
        else:
            landmarks = self._true_landmarks
        return StepMetrics._make(compiled.step_metrics(
            mean, cov, observed, true_pose, landmarks, read, self._last_seen, self._errors,
            self._traces, self._t, self._loop_gap,
        ))  # fmt: skip

    # ------------------------------------------------------------------ hooks of a step
    def _is_terminated(self) -> bool:
        """A wall contact when ``terminate_on_collision``, or every landmark certain to ``done_std``."""
        if self._collided and self.config.terminate_on_collision:
            return True
        return self._worst_variance < self._done_variance

    def _is_truncated(self) -> bool:
        """The step limit (``config.max_episode_steps``, which a ``gym.make`` TimeLimit sets) is reached."""
        return self._steps >= self._max_steps

    def _info(
        self,
        terms: dict[str, float],
        metrics: StepMetrics,
        truth_gain: float,
        belief_gain: float,
        collided: bool,
    ) -> dict[str, Any]:
        """The step's ``info`` (``ekfslam_gym.envs.info.INFO_KEYS`` describes each key); arrays the filter updates
        in place are copied, the odometry's are new each step."""
        return {
            "step": self._t,
            "true_pose": self._world.pose,
            "pose": self._pose_estimate.copy(),
            "pose_cov": self._pose_cov.copy(),
            "log_det": self._telescoped.log_det,
            "reward_terms": terms,
            "truth_gain": truth_gain,
            "belief_gain": belief_gain,
            "landmarks_seen": metrics.landmarks_seen,
            "collision": collided,
            "collisions": self._collisions,
            "pose_nees": metrics.nees,
            "map_rmse": metrics.rmse,
            "loop_closures": self._loop_closures,
            "path_length": self._path_length,
            "odometry": self._odometry,
            "odometry_cov": self._odometry_cov,
            # A (ids, z) named tuple, not arrays: the number of readings varies, and vector envs stack arrays.
            "readings": self._last_readings,
            "filter_failed": self._filter_failed,
            "false_associations": self._false_associations,
            "missed_associations": self._missed_associations,
        }

    # ------------------------------------------------------------------ pieces
    def _take_views(self) -> None:
        """Fetch the filter's public read-only views once per episode rather than at every step: ``_belief``
        (mean, cov, observed, pose_cov_given_map) and the pose block of cov. They stay current because the
        filter updates its arrays in place."""
        ekf = self._ekf
        self._belief = (ekf.mean, ekf.cov, ekf.observed, ekf.pose_cov_given_map)
        self._pose_estimate = ekf.pose
        self._pose_cov = ekf.pose_cov

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for views in ("_belief", "_pose_estimate", "_pose_cov"):
            state[views] = None  # a pickle would copy them apart from the filter; taken anew on load
        state.pop("_read_odometry", None)  # a bound method of the world: rebound on load
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        if self._ekf is not None:
            self._take_views()
            self._read_odometry = getattr(self._world, ODOMETERS[self.config.filter.motion_model])

    def _mark_and_trail(self) -> int:
        """Update the coverage memory (and the trails when rendering); returns the cells newly covered."""
        mean = self._belief[0]
        new = compiled.mark_coverage(self._memory, mean, self._bounds, *self._coverage_settings)
        if self.render_mode is not None:
            x, y, _ = self._world.pose_tuple
            self._trail_true.append((x, y))
            self._trail_est.append((float(mean[0]), float(mean[1])))
        return new

    def _mark_walls(self) -> None:
        """Mark the wall memory from this control step's scan (the belief image's wall channel), the endpoints
        placed at the pose estimate; the scan is kept for the observation (nothing moves in between)."""
        self._scan = scan = self._world.scan()
        sensor = self.config.sensor
        compiled.mark_walls(
            self._walls, self._belief[0], self._bounds, self.config.observation.memory_resolution, scan,
            self._beam_angles, sensor.scan_max_range,
        )  # fmt: skip

    def _observation(self):
        mean, cov, observed, pose_given_map = self._belief
        time_left = max(0.0, 1.0 - self._steps / self._max_steps)
        scan = self._scan if self._belief_image else self._world.scan()
        compiled.fill_observation(
            self._obs, self._layout.offsets, self._constants, mean, cov, observed, self._telescoped.log_det, pose_given_map,
            scan, self._memory, self._bounds, time_left,
        )  # fmt: skip
        if self._belief_image:
            o = self.config.observation
            compiled.fill_belief_image(
                self._image.reshape(-1), o.belief_size, self._memory, self._walls, self._bounds, mean, cov,
                observed, o.memory_resolution, o.belief_extent,
            )  # fmt: skip
        return self._observation_out()

    def _observation_out(self):
        if self._flat:
            return self._obs.copy()
        observation = self._layout.split(self._obs)
        if self._belief_image:
            observation["belief_image"] = self._image.copy()
        if self._last_action is not None:
            observation["last_action"] = self._last_action.copy()
        return observation

    # ------------------------------------------------------------------ access for agents and evaluation
    @property
    def observation_layout(self) -> ObservationLayout:
        """Where each part of the observation lies (``slices``, ``part(observation, name)``)."""
        return self._layout

    @property
    def filter(self) -> EKFSLAM:
        """The env's filter (read-only views of its state; planners should work on ``filter.copy()``)."""
        self._require_reset()
        return self._ekf

    @property
    def world(self) -> World:
        """The simulator (privileged: true poses and walls, for baselines and evaluation only)."""
        self._require_reset()
        return self._world

    @property
    def true_landmarks(self) -> np.ndarray:
        """The true landmark positions (n, 2) in m, read-only (privileged: for baselines and evaluation)."""
        self._require_reset()
        return _read_only(self._true_landmarks)

    @property
    def slot_truth(self) -> np.ndarray:
        """The true landmark each filter slot holds (n,) int, read-only: its index in ``true_landmarks``, -1 for
        a free slot or one started by clutter; 0..n-1 in order with known association (privileged: for
        evaluation, which scores each slot against the landmark it holds)."""
        self._require_reset()
        return _read_only(self._slot_truth)

    @property
    def bounds(self) -> np.ndarray:
        """The world's extent (xmin, ymin, xmax, ymax) in m, read-only."""
        self._require_reset()
        return _read_only(self._bounds)

    @property
    def coverage_memory(self) -> np.ndarray:
        """Where the sensor has looked, read-only: rows along y from ``bounds``' corner,
        ``observation.memory_resolution`` m per cell, 1 = looked at. The coverage windows are read from it."""
        self._require_reset()
        return _read_only(self._memory)

    @property
    def wall_memory(self) -> np.ndarray:
        """Where the wall scan has hit a wall, read-only, laid out like ``coverage_memory`` (1 = a wall seen
        there, placed at the pose estimate); kept only with ``observation.belief_image`` (ValueError without)."""
        self._require_reset()
        if not self._belief_image:
            raise ValueError("the wall memory is kept only with observation.belief_image")
        return _read_only(self._walls)

    @property
    def elapsed_steps(self) -> int:
        """Control steps taken since the last reset (``info["step"]``; env steps too, unless macro actions)."""
        return self._t

    def _require_reset(self) -> None:
        if self._ekf is None:
            raise gym.error.ResetNeeded("call reset() first")

    # ------------------------------------------------------------------ rendering
    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' or 'human'")
            return None
        if self._ekf is None:
            raise gym.error.ResetNeeded("call reset() before render()")
        from .render import Renderer, Scene

        if self._renderer is None:
            self._renderer = Renderer(
                self.render_mode, fps=self.metadata["render_fps"], options=self.render_options
            )
        ekf, world, cfg = self._ekf, self._world, self.config
        observed = ekf.observed
        scene = Scene(
            bounds=self._bounds,
            walls=np.asarray(world.layout.walls),
            wall_radius=float(world.layout.wall_radius),
            robot_radius=cfg.robot.radius,
            landmarks_true=self._true_landmarks,
            landmarks_est=ekf.landmarks.copy(),
            landmark_covs=ekf.landmark_covs(),
            seen=observed.copy(),
            pose_true=world.pose,
            pose_est=ekf.pose.copy(),
            pose_cov=ekf.pose_cov.copy(),
            read_ids=np.asarray(self._last_readings.ids),
            trail_true=np.array(self._trail_true).reshape(-1, 2),
            trail_est=np.array(self._trail_est).reshape(-1, 2),
            max_range=cfg.sensor.max_range,
            fov=cfg.sensor.fov,
            text=(  # in env steps, the unit of the step limit (a macro action is one step of several controls)
                f"step {self._steps}/{self._max_steps}  log det {self._telescoped.log_det:.1f}  "
                f"landmarks seen {int(observed.sum())}/{ekf.n_landmarks}"
            ),
        )
        return self._renderer.render(scene)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


def _read_only(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.setflags(write=False)
    return view


def _summed(steps: list[ControlStep]) -> tuple[dict[str, float], float, float, float, bool]:
    """(reward terms, reward, truth gain, belief gain, collided) of an env step's control steps: each summed in
    order (a failed control step adds 0), collided if any was."""
    if len(steps) == 1:
        (step,) = steps
        return step.terms, step.reward, step.metrics.truth_gain, step.metrics.belief_gain, step.collided
    terms = dict.fromkeys(steps[0].terms, 0.0)
    reward, truth_gain, belief_gain, collided = 0.0, 0.0, 0.0, False
    for step in steps:
        for name, value in step.terms.items():
            terms[name] += value
        reward += step.reward
        truth_gain += step.metrics.truth_gain
        belief_gain += step.metrics.belief_gain
        collided = collided or step.collided
    return terms, reward, truth_gain, belief_gain, collided
