"""EKFSLAM-v0: a robot whose own EKF-SLAM belief is the observation and whose information gain is the reward."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from .. import compiled
from ..filter.ekf import EKFSLAM, FilterDivergedError
from ..sim.layouts import make_layout
from ..sim.sensor import Readings
from ..sim.world import World
from .actions import clipped_velocity, make_interface
from .config import EnvConfig
from .observation import ObservationLayout, make_memory, observation_constants, observation_space
from .rewards import REWARD_TERMS

ODOMETERS = {"odometry": "odometry", "wheels": "wheel_odometry", "velocity": "velocity_odometry"}


class EKFSLAMEnv(gym.Env):
    """Active SLAM: drive a differential-drive robot so that its own EKF-SLAM map becomes certain.

    ## Description
    A pymunk-simulated differential-drive robot moves among walls and point landmarks (a layout generated anew
    at every reset: an open ``arena``, ``rooms`` with doorways, or a corridor ``loop``). A range-bearing sensor
    reads the landmarks within range and field of view that no wall hides, with Gaussian noise and known
    identities; noisy odometry reports the robot's motion. An EKF-SLAM inside the env fuses both (Thrun, Burgard
    & Fox, *Probabilistic Robotics*, ch. 10). The agent sees the filter's belief, never the true map, and is
    paid for the information it gains.

    ## Action Space
    ``Box(-1, 1, (2,), float32)``: (forward speed, turn rate) as fractions of ``robot.v_max`` (m/s) and
    ``robot.omega_max`` (rad/s). Values outside [-1, 1] are clipped; NaN, inf or a wrong shape raise
    ``ValueError`` and change nothing. That is ``action.kind = "velocity"`` with one control step per env step;
    the ``action`` section offers macro actions, each driven for up to ``action.hold`` control steps
    (``ekfslam_gym.envs.actions``): ``primitives``, ``Discrete(9)``, one of the greedy planner's motion
    primitives (``PRIMITIVES``), held (with ``action.guard`` m, a control step that would bring the robot
    within that distance of a wall the scan shows ahead keeps only its turn, and one that finds it already
    within that distance backs off, turn kept); ``waypoint``,
    ``Box(-1, 1, (2,))``, a goal (forward, left) x ``action.waypoint_radius`` m from the estimated pose,
    driven by a controller that sees only the pose estimate and the wall scan, until reached, blocked by a
    wall, or ``hold`` steps. A macro step's reward is
    the sum of its control steps' rewards; ``info["reward_terms"]`` sums each term over them, and
    ``info["inner_steps"]`` and ``info["inner_actions"]`` say what ran.

    ## Observation Space
    ``Box(-5, 5, (D,), float32)`` with D = 4 + 3 + 4k + 3 + B + G^2 + C^2 (164 by default: k = 8 landmark
    slots, B = 16 scan beams, a 9 x 9 robot-centred window of the coverage memory and a coarse 5 x 5 one), or
    with ``observation.kind = "dict"`` a ``Dict`` of the same parts: ``pose``, ``pose_cov``, ``landmarks``,
    ``globals``, ``scan``, ``coverage``, ``coverage_coarse``. ``env.observation_layout`` (an
    ``ObservationLayout``) says where each part lies, for both kinds; ``ekfslam_gym.envs.observation``
    describes every entry and its normalisation. The time-left entry of ``globals`` falls from 1 at reset to
    exactly 0 at the step limit in force (see Episode End).

    Memory and a map, for a convolutional policy: with ``observation = {"kind": "dict", "belief_image": True}``
    (off by default; a ``box`` observation with it raises ``ValueError``) the Dict gains ``belief_image``,
    ``Box(0, 1, (3, S, S), float32)``, S = ``observation.belief_size`` (16) cells reaching
    ``observation.belief_extent`` m (8) to each side, centred on the pose estimate and turned with its heading
    like the coverage window. Channel 0 is the coverage memory; 1 the seen landmarks' estimates, each in its
    cell valued by its certainty 1 / (1 + sqrt(tr Sigma_jj) / cell size); 2 the walls the scan has hit, kept in
    a wall memory (``wall_memory``, laid out like ``coverage_memory``) that every control step marks at the
    scan's endpoints placed from the pose estimate. All of it comes from the belief, never from the true pose,
    landmarks or walls; ``ekfslam_gym.agents.extractors.BeliefCNN`` reads it (``configs/ppo_belief_cnn.yaml``).
    With ``observation.last_action`` (Dict only, off by default) the Dict gains ``last_action``, the action the
    last env step executed, zeros after reset: a float32 one-hot ``Box(0, 1, (K,))`` of the primitive in a
    primitives env, else the clipped action as the action space's Box. It is the policy's own commitment,
    which a planner it imitates keeps and a feed-forward policy otherwise cannot see.

    ## Rewards
    The sum of the terms in ``info["reward_terms"]``, those with a non-zero weight in ``reward`` (the names and
    default weights are ``ekfslam_gym.envs.rewards.REWARD_TERMS``; each term is the hook
    ``_reward_<name>(weight)``):
    ``info_gain`` = log det Sigma_{t-1} - log det Sigma_t of the filter's full, fixed-size covariance (weight 1
    by default), so an episode's information-gain terms sum to log det Sigma_0 - log det Sigma_T. Unseen
    landmarks are carried at the bounded prior ``filter.landmark_prior`` (100 m^2), so discovering one pays
    ln(landmark_prior^2 / det(Gz Q Gz^T)) = ln(landmark_prior^2 / (r^2 range_std^2 bearing_std^2)), about
    23.3 - 2 ln r nats for a landmark first read at r m with the default sensor; the pose starts at
    ``filter.pose_prior``.
    ``collision`` = -1 per step in contact with a wall (weight 1 by default). Optional: ``a_opt``, ``e_opt``
    (drops of ln trace and ln lambda_max of Sigma), ``control_effort`` (-w |a|^2), ``step_cost`` (-w per step),
    ``coverage`` (w per m^2 the sensor looks at for the first time: an exploration shaping for training),
    ``map_variance`` (w times ``info["belief_gain"]``, the drop of the seen landmarks' summed position
    variances in m^2: it pays for revisits and loop closures that make the mapped part more accurate, never
    for a discovery, since a landmark enters the sum only from the step after its first reading),
    ``pose_variance`` (-w tr Sigma_xy, the pose estimate's position variance in m^2, each control step: a cost
    on being lost, which pays for staying localised and closing loops; landmarks first seen from an uncertain
    pose are placed as uncertainly, so the map's absolute accuracy inherits it),
    ``pose_error`` (-w |(x, y) estimate - true|^2 in m^2, each control step: ``pose_variance``'s counterpart in
    the truth, which also charges a pose that has gone wrong while the filter is sure of it; it reads the true
    pose, so it is a training signal only, like an asymmetric critic's, and the observation stays the belief),
    ``map_accuracy`` (w times the drop of ln R, R = sqrt(mean_j tr Sigma_jj) over the landmarks seen, the
    landmark RMSE a consistent filter expects; the terms sum to w ln(R_first / R_final) from the first step
    with a landmark seen, so a discovery placed less certainly than the map so far costs and a loop closure
    pays: beside ``info_gain``, which pays for certainty, it weighs the map's accuracy), ``map_error`` (w times
    the drop of the seen landmarks' true mean squared position error, ``info["map_rmse"]`` squared, from the
    first step with a landmark seen: ``map_accuracy``'s counterpart in the truth, which telescopes to
    w (MSE_first - MSE_final), the scored landmark RMSE squared; it reads the true landmarks, so it is a
    training signal only, like ``pose_error``).

    Standing still earns little: every prediction adds odometry noise (the noise floor), a negative term, and
    re-observing the same landmarks pays ever less (the information about them grows like ln t). Because the
    terms telescope, the most any policy can collect is log det Sigma_0 - log det Sigma_T: it is bounded by
    what remains unknown, and a landmark seen once already has paid most of what it ever will. Exploring pays
    the discovery terms; closing a loop pays the pose and map correlations it removes.

    Belief beside truth (info; the truth gain is never part of the reward, the belief gain only as the
    optional ``map_variance`` term): the gain the filter believes in, in nats and unweighted, is the drop of
    ``info["log_det"]`` from one env step to the next (``reward_terms["info_gain"]`` is it times its weight,
    and absent at weight 0). ``info["truth_gain"]`` (m^2) is the drop, over the step,
    of the summed squared position errors |estimate - true|^2 of the landmarks seen both before and after it
    (with unknown association: the slots holding a true landmark, each against the landmark it holds). A
    landmark first seen in a step enters the sum from the next step on, so its initial error counts as no
    loss; the pose is not included. Over an episode with known association the truth gains sum to
    sum_j (e_j at first sight - e_j at the end). ``info["belief_gain"]`` (m^2) is its counterpart in the
    belief, over exactly the same landmarks (slots): the drop of the sum of their marginal position variances
    tr Sigma_jj (the trace of each 2x2 block), which is what a consistent filter expects the squared error to
    drop by (E e_j = tr Sigma_jj); with known association the belief gains sum over an episode to
    sum_j (tr Sigma_jj at first sight - tr Sigma_jj at the end). Both are 0 at reset and on a failed step; a
    macro step sums each over its control steps. The evaluation reports, per episode, the correlation of the
    belief and truth gains and the final map NEES (``ekfslam_gym.evaluation.episodes``): a policy paid for
    information that makes the map no better shows a low correlation, and an over-confident map a NEES above 1.

    ## Starting State
    The robot at the layout's start pose, known to the filter (pose prior ``filter.pose_prior``); ``reset``
    takes a first reading and corrects, and Sigma_0 is the belief after that (``info["log_det"]``).

    ## Episode End
    Terminated (``_is_terminated``): on a wall contact if ``terminate_on_collision``; when every landmark's
    marginal standard deviation is below ``done_std`` m; when the filter fails numerically
    (``info["filter_failed"]``, never an exception). Truncated (``_is_truncated``): after N env steps, where N, the
    step limit, is one number for the TimeLimit wrapper of ``gym.make``, the env's own truncation and the
    time-left entry, and ``env.spec.max_episode_steps == env.unwrapped.config.max_episode_steps == N``:
    the registered limit by default (500, 800, 1000, in each id's spec); ``gym.make(id, max_episode_steps=N)``
    sets it (the ``HorizonSync`` wrapper, right above the TimeLimit, passes N to ``set_max_episode_steps``); so
    does a config whose ``max_episode_steps`` differs from the registered limit, e.g.
    ``gym.make(id, config={"max_episode_steps": N})`` (the TimeLimit is rebuilt with N). Two different limits,
    neither the registered one, raise ``ValueError``. Built without ``gym.make`` (or with
    ``max_episode_steps=-1``), the env truncates itself at ``config.max_episode_steps``.

    ## Data association
    By default the filter is told which landmark each reading comes from (``filter.association = "known"``).
    ``sensor.detection_prob`` < 1 drops readings of visible landmarks; ``sensor.clutter_rate`` > 0 adds false
    readings (a Poisson number per step, uniform in range and bearing over the field of view, true id -1),
    which known association drops as an oracle would. With ``filter.association`` ``"nearest"`` or ``"jcbc"``
    (joint compatibility branch and bound, Neira & Tardos 2001) the filter gets the readings without ids, in
    bearing order, and associates them itself (``EKFSLAM.correct_unknown``): a reading inside the
    ``filter.gate_prob`` chi-squared gate of a landmark may be matched to it; one outside the
    ``filter.new_gate_prob`` gate of every landmark starts a new one in the first free slot, tentatively (it is
    forgotten, its slot freed, unless matched again within ``filter.confirm_steps`` steps); readings between
    the gates are discarded. A slot then need not hold the landmark of the same index: ``slot_truth`` (n,)
    names the true landmark each slot holds (-1: free or started by clutter), and ``map_rmse``,
    ``landmarks_seen`` and the ``done_std`` end score each slot against the landmark it holds (a slot of
    clutter counts as unseen). ``info["false_associations"]`` counts, over the episode, readings matched to a
    slot holding another landmark or clutter matched to any slot; ``info["missed_associations"]`` readings of
    true landmarks neither matched nor starting a landmark; both are 0 with known association.
    ``info["readings"]`` holds the readings the filter used, their ids the slots it used them for.

    ## Arguments
    ``gymnasium.make("EKFSLAM-v0", config=None, render_mode=None, **overrides)``: ``config`` is an
    ``EnvConfig``, a path to a YAML file (see ``configs/env/``) or a mapping of sections, and replaces the id's
    preset; ``overrides`` are sections given as keyword arguments, applied on top of it, e.g.
    ``world={"n_landmarks": 50}, reward={"collision": 2.0}``; the filter's odometry model and linearisation
    are ``filter={"motion_model": "wheels", "variant": "fej"}`` (see ``ekfslam_gym.filter.FilterSettings``). A bad value raises
    ``ValueError`` naming the field. ``max_episode_steps`` given to ``gym.make`` is ``gym.make``'s own argument (see Episode End); given
    to ``EKFSLAMEnv(...)`` directly it is a config override.

    After ``reset``, agents and evaluation read the belief through public, read-only views: ``filter``
    (``mean``, ``cov``, ``observed``, ...), ``observation_layout``, ``bounds``, ``coverage_memory``,
    ``wall_memory`` (with the belief image), ``elapsed_steps``; ``world`` and ``true_landmarks`` are privileged
    (baselines and evaluation only).

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

        self._layout = ObservationLayout.from_config(config.observation, config.sensor)
        self._interface = make_interface(config)
        self.action_space = self._interface.space
        # One control step per env step (the default): step() takes its direct path, as fast as before.
        self._single = config.action.kind == "velocity" and config.action.steps == 1
        self._hold = config.action.steps
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
        # The reward hooks of the terms with a non-zero weight, in REWARD_TERMS order: (name, weight, hook).
        self._reward_hooks = tuple(
            (term.name, weight, getattr(type(self), f"_reward_{term.name}"))
            for term in REWARD_TERMS
            if (weight := float(getattr(config.reward, term.name)))
        )
        # Constants of the step, read once here rather than through the config at every step.
        self._v_max, self._omega_max = config.robot.v_max, config.robot.omega_max
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
            layout.n_landmarks, f, dt=cfg.dt, measurement_noise=cfg.sensor.cov, initial_pose=layout.start,
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
        self._belief_gain = 0.0
        self._action = (0.0, 0.0)
        if self._last_action is not None:
            self._last_action[:] = 0.0
        self._trail_true: list[tuple[float, float]] = []
        self._trail_est: list[tuple[float, float]] = []

        readings = self._world.sense(rng)
        if self._unknown:
            read = self._correct_unknown(readings)  # keeps what the filter used as _last_readings
        else:
            ekf.correct(readings.ids, readings.z)
            read = readings.ids
            self._last_readings = readings
        self._log_det = self._prev_log_det = ekf.log_det
        self._belief = self._belief_views()
        cov = self._belief[1]
        weights = self.config.reward
        self._trace = float(np.trace(cov)) if weights.a_opt else 0.0
        self._lambda_max = self._largest_eigenvalue(cov) if weights.e_opt else 0.0
        self._odometry = np.zeros(2 if f.motion_model == "velocity" else 3)
        self._odometry_cov = np.zeros((self._odometry.size, self._odometry.size))
        self._newly_covered = self._mark_and_trail()
        if self._belief_image:
            self._mark_walls()
        nees, rmse, _, self._worst_variance, seen, _, _ = self._step_metrics(read)
        self._log_map_rms = self._log_map_rms_std() if weights.map_accuracy else math.nan
        self._map_mse = self._step_mse = rmse * rmse if seen else math.nan
        info = self._info({"info_gain": 0.0}, nees, rmse, seen, 0.0, 0.0)
        if self.render_mode == "human":
            self.render()
        return self._observation(), info

    def step(self, action):
        if self._ekf is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        if self._single:
            a0, a1 = clipped_velocity(action)
            if self._last_action is not None:
                self._last_action[:] = (a0, a1)
            terms, reward, terminated, nees, rmse, seen, truth_gain, belief_gain, failed = self._control_step(
                a0, a1
            )
            self._steps += 1
            if failed:
                return self._failed_step()
            truncated = not terminated and self._is_truncated()
            info = self._info(terms, nees, rmse, seen, truth_gain, belief_gain)
            if self.render_mode == "human":
                self.render()
            return self._observation(), reward, terminated, truncated, info
        return self._macro_step(action)

    def _macro_step(self, action):
        """Up to ``action.hold`` control steps of one macro action (see ``ekfslam_gym.envs.actions``)."""
        interface = self._interface
        mean = self._belief[0]
        interface.begin(action, mean[:3])
        if self._last_action is not None:
            interface.encode(self._last_action)
        totals: dict[str, float] = {}
        reward, truth_gain, belief_gain, collided, terminated, inner = 0.0, 0.0, 0.0, False, False, []
        for _ in range(self._hold):
            command = interface.command(mean[:3], self._world.scan)
            if command is None and inner:
                break
            a0, a1 = (0.0, 0.0) if command is None else command
            terms, step_reward, terminated, nees, rmse, seen, step_truth, step_belief, failed = (
                self._control_step(a0, a1)
            )
            inner.append((a0, a1))
            if failed:
                self._steps += 1
                return self._failed_step(inner)
            reward += step_reward
            truth_gain += step_truth
            belief_gain += step_belief
            collided = collided or self._collided
            for name, value in terms.items():
                totals[name] = totals.get(name, 0.0) + value
            if terminated:
                break
        self._steps += 1
        truncated = not terminated and self._is_truncated()
        info = self._info(totals, nees, rmse, seen, truth_gain, belief_gain)
        info["collision"] = collided
        info["inner_steps"] = len(inner)
        info["inner_actions"] = np.array(inner, dtype=np.float64)
        if self.render_mode == "human":
            self.render()
        return self._observation(), reward, terminated, truncated, info

    def _control_step(self, a0: float, a1: float):
        """One control step of ``dt`` with the normalised command (a0, a1) already clipped: physics, odometry,
        readings, filter, reward terms and metrics. Returns (terms, reward, terminated, nees, rmse, seen,
        truth_gain, belief_gain, failed); the caller builds the observation and info once per env step."""
        ekf = self._ekf
        world, rng = self._world, self.np_random
        x0, y0, _ = world.pose_tuple
        collided = world.step(a0 * self._v_max, a1 * self._omega_max)
        x1, y1, _ = world.pose_tuple
        self._path_length += math.hypot(x1 - x0, y1 - y0)
        self._collisions += collided
        if self._wheels:
            odometry, readings = world.wheel_odometry_and_readings(rng)
        else:
            odometry = self._read_odometry(rng)
            readings = world.sense(rng)
        self._odometry, self._odometry_cov, self._last_readings = odometry.u, odometry.cov, readings
        self._t += 1
        self._action = (a0, a1)
        self._collided = collided

        unknown = self._unknown
        try:
            if unknown:
                ekf.predict(odometry.u, control_cov=odometry.cov)
                read = self._correct_unknown(readings)
            else:
                ekf.update(odometry.u, odometry.cov, readings.ids, readings.z)
                read = readings.ids
            failed = not math.isfinite(ekf.log_det)
        except FilterDivergedError:
            failed = True
        if failed:
            return None, 0.0, True, math.nan, math.nan, 0, 0.0, 0.0, True

        self._prev_log_det, self._log_det = self._log_det, ekf.log_det
        self._newly_covered = self._mark_and_trail()
        if self._belief_image:
            self._mark_walls()
        nees, rmse, closures, self._worst_variance, seen, truth_gain, belief_gain = self._step_metrics(read)
        self._loop_closures += closures
        self._belief_gain = belief_gain
        self._step_mse = rmse * rmse if seen else math.nan
        terms = self._rewards()
        reward = sum(terms.values(), 0.0)
        return terms, reward, self._is_terminated(), nees, rmse, seen, truth_gain, belief_gain, False

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
        slots, new, forgotten, _ = ekf.correct_unknown(
            z, f.association, f.gate_prob, f.new_gate_prob, confirm_within=f.confirm_steps
        )
        false, missed, read, read_z = compiled.tally_associations(
            ids, z, slots, new, forgotten, ekf.observed, self._slot_truth, self._true_landmarks,
            self._slot_landmarks, self._slot_valid,
        )  # fmt: skip
        self._false_associations += false
        self._missed_associations += missed
        self._last_readings = Readings(read, read_z)
        return read

    def _step_metrics(self, read: np.ndarray):
        """``compiled.step_metrics`` of the step, ``read`` the slots the filter used. With known association
        slot j is landmark j; otherwise each slot is scored against the true landmark it holds (slots of
        clutter and free slots count as unseen, so the done_std end waits for every slot to hold one)."""
        mean, cov, observed, _ = self._belief
        if self._unknown:
            observed, landmarks = self._slot_valid, self._slot_landmarks
        else:
            landmarks = self._true_landmarks
        return compiled.step_metrics(
            mean, cov, observed, self._world.pose_tuple, landmarks, read, self._last_seen, self._errors,
            self._traces, self._t, self.config.loop_gap,
        )  # fmt: skip

    def _failed_step(self, inner: list | None = None):
        """The step on which the filter failed numerically: terminated, reward 0, the last observation."""
        self._filter_failed = True
        observed = self._belief[2]
        info = self._info({"info_gain": 0.0}, math.nan, math.nan, int(np.count_nonzero(observed)), 0.0, 0.0)
        if inner is not None:
            info["inner_steps"] = len(inner)
            info["inner_actions"] = np.array(inner, dtype=np.float64)
        return self._observation_out(), 0.0, True, False, info

    # ------------------------------------------------------------------ hooks of a step
    def _rewards(self) -> dict[str, float]:
        """The weighted reward terms by name, those with a non-zero weight only (``info["reward_terms"]``);
        the reward is their sum. Each comes from its hook ``_reward_<name>(weight)`` (see ``rewards``)."""
        return {name: hook(self, weight) for name, weight, hook in self._reward_hooks}

    def _reward_info_gain(self, weight: float) -> float:
        return weight * (self._prev_log_det - self._log_det)

    def _reward_a_opt(self, weight: float) -> float:
        trace = float(np.trace(self._belief[1]))
        value = weight * (math.log(self._trace) - math.log(trace))
        self._trace = trace
        return value

    def _reward_e_opt(self, weight: float) -> float:
        largest = self._largest_eigenvalue(self._belief[1])
        value = weight * (math.log(self._lambda_max) - math.log(largest))
        self._lambda_max = largest
        return value

    def _reward_collision(self, weight: float) -> float:
        return -weight * self._collided

    def _reward_control_effort(self, weight: float) -> float:
        a0, a1 = self._action
        return -weight * (a0 * a0 + a1 * a1)

    def _reward_step_cost(self, weight: float) -> float:
        return -weight

    def _reward_map_variance(self, weight: float) -> float:
        return weight * self._belief_gain

    def _reward_pose_variance(self, weight: float) -> float:
        cov = self._belief[1]
        return -weight * float(cov[0, 0] + cov[1, 1])

    def _reward_pose_error(self, weight: float) -> float:
        mean = self._belief[0]
        x, y, _ = self._world.pose_tuple
        dx, dy = float(mean[0]) - x, float(mean[1]) - y
        return -weight * (dx * dx + dy * dy)

    def _reward_map_accuracy(self, weight: float) -> float:
        previous, self._log_map_rms = self._log_map_rms, self._log_map_rms_std()
        if math.isnan(previous) or math.isnan(self._log_map_rms):
            return 0.0  # no landmark seen yet: the sum starts at the first one
        return weight * (previous - self._log_map_rms)

    def _reward_map_error(self, weight: float) -> float:
        previous, self._map_mse = self._map_mse, self._step_mse
        if math.isnan(previous) or math.isnan(self._map_mse):
            return 0.0  # no landmark seen yet: the sum starts at the first one
        return weight * (previous - self._map_mse)

    def _log_map_rms_std(self) -> float:
        """ln sqrt(mean_j tr Sigma_jj) over the landmarks (slots) scored as seen by the last ``_step_metrics``,
        whose ``_traces`` it reads; NaN when none is seen."""
        seen = self._slot_valid if self._unknown else self._belief[2]
        if not seen.any():
            return math.nan
        return 0.5 * math.log(float(self._traces[seen].mean()))

    def _reward_coverage(self, weight: float) -> float:
        return weight * self._newly_covered * self.config.observation.memory_resolution**2

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
        nees: float,
        rmse: float,
        landmarks_seen: int,
        truth_gain: float,
        belief_gain: float,
    ) -> dict[str, Any]:
        """The step's ``info``; arrays the filter updates in place are copied, the odometry's are new each step."""
        mean, cov, _, _ = self._belief
        return {
            "step": self._t,
            "true_pose": self._world.pose,
            "pose": mean[:3].copy(),
            "pose_cov": cov[:3, :3].copy(),
            "log_det": self._log_det,
            "reward_terms": terms,
            "truth_gain": truth_gain,
            "belief_gain": belief_gain,
            "landmarks_seen": landmarks_seen,
            "collision": self._collided,
            "collisions": self._collisions,
            "pose_nees": nees,
            "map_rmse": rmse,
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
    def _belief_views(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The filter's (mean, cov, observed, pose_cov_given_map): its public read-only views, fetched once per
        episode rather than at every step. They stay current because the filter updates its arrays in place."""
        ekf = self._ekf
        return ekf.mean, ekf.cov, ekf.observed, ekf.pose_cov_given_map

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_belief"] = None  # views: a pickle would copy them apart from the filter; rebuilt on load
        state.pop("_read_odometry", None)  # a bound method of the world: rebound on load
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        if self._ekf is not None:
            self._belief = self._belief_views()
            self._read_odometry = getattr(self._world, ODOMETERS[self.config.filter.motion_model])

    @staticmethod
    def _largest_eigenvalue(cov: np.ndarray) -> float:
        return float(np.linalg.eigvalsh(cov)[-1])

    def _mark_and_trail(self) -> int:
        """Update the coverage memory (and the trails when rendering); returns the cells newly covered."""
        mean = self._belief[0]
        sensor = self.config.sensor
        new = compiled.mark_coverage(
            self._memory, mean, self._bounds, self.config.observation.memory_resolution, sensor.max_range,
            sensor.fov,
        )  # fmt: skip
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
            self._obs, self._layout.offsets, self._constants, mean, cov, observed, self._log_det, pose_given_map,
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
            self._renderer = Renderer(self.render_mode, fps=self.metadata["render_fps"])
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
            text=f"t={self._t}  log det={self._log_det:.1f}  seen={int(observed.sum())}/{ekf.n_landmarks}",
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
