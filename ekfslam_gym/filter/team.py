"""Centralised EKF-SLAM for a team of robots: every robot's pose and every landmark in one state.

The state is mu = (pose_1, ..., pose_N, m_1, ..., m_n): robot r (0-based) at entries 3r..3r+2 as
(x, y, theta), landmark s at 3N + 2s as (x, y); size 3N + 2n, with its covariance Sigma. Each robot moves by the
same motion models as ``EKFSLAM`` (one ``FilterSettings`` for the team), reads landmarks with its range-bearing
sensor, and reads other robots: the range and bearing of robot j's position in robot i's frame
(``team_models.robot_range_bearing``), a relative measurement fused with its Jacobians in both poses. This is
the centralised cooperative SLAM of Fenwick, Newman & Leonard (ICRA 2002) and, for localisation, Roumeliotis &
Bekey (IEEE T-RA 18(5), 2002).

API (mirrors ``EKFSLAM``; ``robot`` is a 0-based robot index, ``ids`` 0-based landmark slots)::

    team = TeamEKF(n_robots, n_landmarks, settings=None, *, dt=0.1, wheel_base=0.3,
                   motion_noise=..., measurement_noise=..., robot_measurement_noise=None,
                   initial_poses=None, initial_pose_covs=None, min_range=1e-3, **setting_changes)
    team.predict(robot, control, *, motion_cov=None, control_cov=None) -> d log det
    team.correct(robot, ids, readings, *, measurement_cov=None) -> d log det       # landmarks
    team.correct_robots(robot, targets, readings, *, measurement_cov=None) -> d log det   # other robots
    team.associate(robot, readings, AssociationSettings(kind="jcbc")) -> slots   # landmarks without their ids
    team.correct_unknown(robot, readings, AssociationSettings(...)) -> UnknownCorrection
    team.forget(slot) -> d log det
    team.reading_nis(robot, readings, *, landmarks=None, robots=None) -> NIS per reading
    team.resync() -> drift;  team.copy()
    team.mean, .cov, .log_det, .observed, .landmarks (n, 2), .landmark_cov(s), .landmark_covs()
    team.poses (N, 3), .pose(robot), .pose_cov(robot) (3, 3), .poses_cov (3N, 3N),
    team.pose_cov_given_map (3N, 3N), .pose_index(robot), .landmark_index(slot), .state_size

Every call returns the exact change of log det Sigma, kept by the bookkeeping of ``EKFSLAM`` with P the robots'
joint pose covariance conditioned on the map (``team_kernels``), re-synchronised from a Cholesky every
``settings.resync_every`` calls. Landmarks start unseen at the ``landmark_prior`` and are initialised by the
first robot that reads them (``settings.init_mode``), as ``EKFSLAM`` does; ``variant`` (ekf, fej, iekf) and
``update`` (batch, sequential) apply to both kinds of reading. Robot readings name their robots; landmark
readings name their landmarks (``correct``) or are associated with the team's map (``correct_unknown``: a robot's
pose and the map are a single robot's state, so ``EKFSLAM``'s nearest-neighbour and JCBC association serve
unchanged). With one robot, ``TeamEKF(1, n, ...)`` gives ``EKFSLAM(n, ...)``'s results.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

from .. import compiled
from ..angles import wrap_angle
from . import association, codes, team_kernels
from .association import UnknownCorrection
from .ekf import (
    _CONTROL_WIDTH,
    _MODEL_CODES,
    _VARIANT_CODES,
    COURSE_MEASUREMENT_NOISE,
    COURSE_MOTION_NOISE,
    EKFSLAM,
    FilterDivergedError,
    _as_covariance,
    _check_positive_definite,
    _motion_inputs,
    _read_only,
    _settings,
)
from .settings import AssociationSettings, FilterSettings

__all__ = ["TeamEKF"]


def _count(value: Any, name: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


class TeamEKF:
    """EKF-SLAM over ``n_robots`` robots' poses and ``n_landmarks`` point landmarks (see the module docstring).

    Args:
        n_robots: robots in the team (>= 1).
        n_landmarks: landmark slots (fixed; readings name them by 0-based index).
        settings: ``FilterSettings`` shared by the team (motion model, variant, initialisation, update mode,
            priors, resync period); default ``FilterSettings()``. Association is chosen per call
            (``correct_unknown``'s arguments).
        dt, wheel_base, motion_noise, measurement_noise, min_range: as ``EKFSLAM``'s, for every robot.
        robot_measurement_noise: Q of one robot-to-robot (range, bearing) reading; default
            ``measurement_noise``.
        initial_poses: (N, 3) starting pose means (default all at the origin).
        initial_pose_covs: each robot's starting pose covariance: a scalar, a (3,) diagonal or (3, 3) for all,
            or (N, 3, 3) one each; default ``settings.pose_prior`` times the identity.
        **changes: fields of ``FilterSettings`` to change from ``settings``.
    """

    def __init__(
        self,
        n_robots: int,
        n_landmarks: int,
        settings: FilterSettings | None = None,
        *,
        dt: float = 0.1,
        wheel_base: float = 0.3,
        motion_noise=COURSE_MOTION_NOISE,
        measurement_noise=COURSE_MEASUREMENT_NOISE,
        robot_measurement_noise=None,
        initial_poses=None,
        initial_pose_covs=None,
        min_range: float = 1e-3,
        **changes: Any,
    ) -> None:
        settings = _settings(settings, changes)
        self.n_robots = _count(n_robots, "n_robots", 1)
        self.n_landmarks = _count(n_landmarks, "n_landmarks", 0)
        for name, value in (("wheel_base", wheel_base), ("dt", dt), ("min_range", min_range)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        self.settings = settings
        self.motion_model = settings.motion_model
        self.variant = settings.variant
        self.iterations = settings.iterations
        self.init_mode = settings.init_mode
        self.update_mode = settings.update
        self.resync_every = settings.resync_every
        self.landmark_prior = float(settings.landmark_prior)
        self.dt = float(dt)
        self.wheel_base = float(wheel_base)
        self.min_range = float(min_range)
        self.motion_noise = _as_covariance(motion_noise, 3, "motion_noise")
        self.measurement_noise = _as_covariance(measurement_noise, 2, "measurement_noise")
        _check_positive_definite(self.measurement_noise, "measurement_noise")
        self.robot_measurement_noise = (
            self.measurement_noise
            if robot_measurement_noise is None
            else _as_covariance(robot_measurement_noise, 2, "robot_measurement_noise")
        )
        _check_positive_definite(self.robot_measurement_noise, "robot_measurement_noise")
        self._model_code = _MODEL_CODES[self.motion_model]
        self._variant_code = _VARIANT_CODES[self.variant]
        self._fej = self.variant == "fej"
        self._width = _CONTROL_WIDTH[self.motion_model]

        pose_size = 3 * self.n_robots
        size = pose_size + 2 * self.n_landmarks
        self._mean = np.zeros(size)
        if initial_poses is not None:
            poses = np.asarray(initial_poses, dtype=float)
            if poses.shape != (self.n_robots, 3) or not np.all(np.isfinite(poses)):
                raise ValueError(
                    f"initial_poses must be ({self.n_robots}, 3) finite numbers, got {poses.shape}"
                )
            poses = poses.copy()
            poses[:, 2] = [wrap_angle(a) for a in poses[:, 2]]
            self._mean[:pose_size] = poses.reshape(-1)
        pose_covs = self._pose_covs(settings.pose_prior if initial_pose_covs is None else initial_pose_covs)
        self._cov = np.zeros((size, size))
        for r in range(self.n_robots):
            self._cov[3 * r : 3 * r + 3, 3 * r : 3 * r + 3] = pose_covs[r]
        idx = np.arange(pose_size, size)
        self._cov[idx, idx] = self.landmark_prior
        self._observed = np.zeros(self.n_landmarks, dtype=bool)
        self._prior_poses = self._mean[:pose_size].reshape(self.n_robots, 3).copy()
        self._first = np.zeros((self.n_landmarks, 2))
        # correct_unknown's tentative landmarks: corrections left to be matched again before being forgotten.
        self._tentative = np.zeros(self.n_landmarks, dtype=np.int64)
        self._started_by = np.zeros(self.n_landmarks, dtype=np.int64)  # the robot whose calls count them down
        self._association_cache: dict = {}
        self._G_used = np.eye(3)
        self._control = np.zeros(3)
        self._P = np.zeros((pose_size, pose_size))
        self._log_det = -np.inf
        self._tracking = False
        self._calls_since_resync = 0
        self._start_tracking(pose_covs)

    def _pose_covs(self, value) -> np.ndarray:
        arr = np.asarray(value, dtype=float)
        if arr.ndim == 3:
            if arr.shape != (self.n_robots, 3, 3):
                raise ValueError(f"initial_pose_covs must be ({self.n_robots}, 3, 3) when given per robot")
            return np.stack([_as_covariance(c, 3, f"initial_pose_covs[{r}]") for r, c in enumerate(arr)])
        one = _as_covariance(arr, 3, "initial_pose_covs")
        return np.repeat(one[None], self.n_robots, axis=0)

    def _start_tracking(self, pose_covs: np.ndarray) -> None:
        """log det Sigma and P of the initial block-diagonal Sigma in O(N); a singular pose prior (the course's
        zero) leaves tracking to the first ``resync`` that finds Sigma definite."""
        try:
            chols = np.linalg.cholesky(pose_covs)
        except np.linalg.LinAlgError:
            return
        self._log_det = 2.0 * float(np.sum(np.log(np.diagonal(chols, axis1=1, axis2=2)))) + (
            2 * self.n_landmarks * math.log(self.landmark_prior)
        )
        for r in range(self.n_robots):
            self._P[3 * r : 3 * r + 3, 3 * r : 3 * r + 3] = pose_covs[r]
        self._tracking = True

    # ------------------------------------------------------------------ state
    @property
    def state_size(self) -> int:
        return self._mean.shape[0]

    def pose_index(self, robot: int) -> int:
        """The state index of robot ``robot``'s x (its y and theta follow)."""
        return 3 * self._robot(robot)

    def landmark_index(self, slot: int) -> int:
        """The state index of landmark ``slot``'s x (its y follows)."""
        if not 0 <= slot < self.n_landmarks:
            raise IndexError(f"landmark index {slot} outside [0, {self.n_landmarks})")
        return 3 * self.n_robots + 2 * slot

    @property
    def mean(self) -> np.ndarray:
        """The full state mean (3N + 2n,), read-only view."""
        return _read_only(self._mean)

    @property
    def cov(self) -> np.ndarray:
        """The full covariance Sigma, read-only view."""
        return _read_only(self._cov)

    @property
    def poses(self) -> np.ndarray:
        """Every robot's pose mean (N, 3), read-only view."""
        return _read_only(self._mean[: 3 * self.n_robots].reshape(self.n_robots, 3))

    def pose(self, robot: int) -> np.ndarray:
        """Robot ``robot``'s pose mean (3,), read-only view."""
        o = self.pose_index(robot)
        return _read_only(self._mean[o : o + 3])

    def pose_cov(self, robot: int) -> np.ndarray:
        """Robot ``robot``'s marginal pose covariance (3, 3), read-only view."""
        o = self.pose_index(robot)
        return _read_only(self._cov[o : o + 3, o : o + 3])

    @property
    def poses_cov(self) -> np.ndarray:
        """The robots' joint pose covariance (3N, 3N) (cross-covariances included), read-only view."""
        size = 3 * self.n_robots
        return _read_only(self._cov[:size, :size])

    @property
    def landmarks(self) -> np.ndarray:
        """Landmark means (n, 2); unseen ones hold 0 until initialised."""
        return _read_only(self._mean[3 * self.n_robots :].reshape(-1, 2))

    @property
    def observed(self) -> np.ndarray:
        """Which landmarks have been initialised (n,) bool."""
        return _read_only(self._observed)

    @property
    def log_det(self) -> float:
        """log det Sigma, kept incrementally; -inf while Sigma is singular."""
        return self._log_det

    @property
    def pose_cov_given_map(self) -> np.ndarray:
        """P (3N, 3N), the robots' joint pose covariance conditioned on the map; log det Sigma =
        log det Sigma_mm + log det P. Zeros until Sigma is definite."""
        return _read_only(self._P)

    def landmark_cov(self, index: int) -> np.ndarray:
        """Marginal covariance (2, 2) of landmark ``index`` (0-based), a copy."""
        j = self.landmark_index(index)
        return self._cov[j : j + 2, j : j + 2].copy()

    def landmark_covs(self) -> np.ndarray:
        """Marginal covariances of all landmarks (n, 2, 2), a copy."""
        start = 3 * self.n_robots
        diag = np.diagonal(self._cov)[start:]
        out = np.empty((self.n_landmarks, 2, 2))
        out[:, 0, 0] = diag[0::2]
        out[:, 1, 1] = diag[1::2]
        off = self._cov[start::2, start + 1 :: 2].diagonal() if self.n_landmarks else np.empty(0)
        out[:, 0, 1] = off
        out[:, 1, 0] = off
        return out

    def copy(self) -> TeamEKF:
        """An independent copy (for planners that simulate the filter forward)."""
        return copy.deepcopy(self)

    # ------------------------------------------------------------------ filter
    def predict(self, robot: int, control, *, motion_cov=None, control_cov=None) -> float:
        """Move robot ``robot`` by its control (as ``EKFSLAM.predict``: the model's control, and noise in
        pose space ``motion_cov`` or control space ``control_cov``); returns the change of log det Sigma."""
        robot = self._robot(robot)
        control, noise, in_control_space = _motion_inputs(
            control, self.motion_model, self._width, motion_cov, control_cov, self.motion_noise
        )
        self._control[: self._width] = control
        delta, status = team_kernels.predict(
            self._mean, self._cov, self._P, robot, self._model_code, self._control, self.dt, self.wheel_base,
            np.ascontiguousarray(noise), in_control_space, self._tracking, self._prior_poses, self._fej,
            self._G_used,
        )  # fmt: skip
        if status == codes.BAD_INPUT:
            raise ValueError(f"control and its noise must be finite, got {control!r}")
        if status == codes.NOT_PD:
            raise FilterDivergedError("the robots' pose covariance is no longer positive definite")
        self._after_call(delta)
        return delta

    def correct(self, robot: int, ids, readings, *, measurement_cov=None) -> float:
        """Correct with robot ``robot``'s range-bearing readings (m, 2) of landmarks ``ids`` (m,) (as
        ``EKFSLAM.correct``); returns the change of log det Sigma."""
        robot = self._robot(robot)
        ids = np.ascontiguousarray(np.asarray(ids, dtype=np.int64).reshape(-1))
        readings = self._readings(readings, len(ids))
        Q = self._noise(measurement_cov, self.measurement_noise)
        delta, status, _ = team_kernels.correct(
            self._mean, self._cov, self._P, self._observed, self.n_robots, robot, ids, readings, Q,
            self.min_range, self.init_mode == "course", self.update_mode == "sequential", self._tracking,
            self._variant_code, self.iterations, self._prior_poses, self._first,
        )  # fmt: skip
        if status == codes.BAD_ID:
            raise ValueError(f"landmark ids must lie in [0, {self.n_landmarks}), got {ids.tolist()}")
        self._raise_status(status)
        self._after_call(delta)
        return delta

    def correct_robots(self, robot: int, targets, readings, *, measurement_cov=None) -> float:
        """Correct with robot ``robot``'s range-bearing readings (m, 2) of the positions of robots ``targets``
        (m,) (0-based, not ``robot``): relative measurements, fused with their Jacobians in both poses
        (``team_models.robot_range_bearing``). Noise: ``measurement_cov`` or the constructor's
        ``robot_measurement_noise``. Returns the change of log det Sigma."""
        robot = self._robot(robot)
        targets = np.ascontiguousarray(np.asarray(targets, dtype=np.int64).reshape(-1))
        readings = self._readings(readings, len(targets))
        Q = self._noise(measurement_cov, self.robot_measurement_noise)
        delta, status, _ = team_kernels.correct_robots(
            self._mean, self._cov, self._P, self.n_robots, robot, targets, readings, Q, self.min_range,
            self.update_mode == "sequential", self._tracking, self._variant_code, self.iterations,
            self._prior_poses,
        )  # fmt: skip
        if status == codes.BAD_ID:
            raise ValueError(
                f"targets must be robots in [0, {self.n_robots}) other than the observer {robot}, "
                f"got {targets.tolist()}"
            )
        self._raise_status(status)
        self._after_call(delta)
        return delta

    def reading_nis(self, robot: int, readings, *, landmarks=None, robots=None, measurement_cov=None):
        """Each reading's NIS (2 dof) against the current state, without changing it: robot ``robot``'s
        readings (m, 2) of initialised ``landmarks`` (m,) slots, or of other ``robots`` (m,) (one of the two).
        Noise as ``correct`` or ``correct_robots`` would use it."""
        robot = self._robot(robot)
        if (landmarks is None) == (robots is None):
            raise ValueError("give the readings' landmarks or their robots, not both")
        if landmarks is not None:
            slots = np.asarray(landmarks, dtype=np.int64).reshape(-1)
            if np.any((slots < 0) | (slots >= self.n_landmarks)) or not np.all(self._observed[slots]):
                raise ValueError(f"landmarks must be initialised slots, got {slots.tolist()}")
            cols = 3 * self.n_robots + 2 * slots
            default = self.measurement_noise
        else:
            targets = np.asarray(robots, dtype=np.int64).reshape(-1)
            if np.any((targets < 0) | (targets >= self.n_robots) | (targets == robot)):
                raise ValueError(
                    f"robots must be other robots in [0, {self.n_robots}), got {targets.tolist()}"
                )
            cols = 3 * targets
            default = self.robot_measurement_noise
        z = self._readings(readings, len(cols))
        observers = np.full(len(cols), robot, dtype=np.int64)
        return team_kernels.reading_nis(
            self._mean, self._cov, observers, np.ascontiguousarray(cols), z,
            self._noise(measurement_cov, default), self.min_range,
        )  # fmt: skip

    # ------------------------------------------------------------------ unknown correspondences
    def associate(
        self, robot: int, readings, settings: AssociationSettings, *, measurement_cov=None
    ) -> np.ndarray:
        """The initialised landmark slot each of robot ``robot``'s readings (m, 2) comes from, -1 for none:
        ``EKFSLAM.associate`` on the robot's pose and the map (their joint Gaussian, a marginal of the team's),
        with the same ``AssociationSettings`` (kind, gate_prob). Changes nothing."""
        code, gates, _, _, _ = self._association_options(settings)
        robot = self._robot(robot)
        readings = np.ascontiguousarray(np.asarray(readings, dtype=float).reshape(-1, 2))
        if not np.all(np.isfinite(readings)):
            raise ValueError("readings must be finite")
        slots = np.empty(len(readings), dtype=np.int64)
        mean, cov = self._robot_view(robot)
        compiled.associate(
            mean, cov, self._observed, readings, self._noise(measurement_cov, self.measurement_noise),
            self.min_range, code, gates, association.MAX_NODES, slots, np.empty(len(readings)),
        )  # fmt: skip
        return slots

    def correct_unknown(
        self, robot: int, readings, settings: AssociationSettings, *, measurement_cov=None
    ) -> UnknownCorrection:
        """``EKFSLAM.correct_unknown`` for robot ``robot``'s readings (m, 2): associate them with the team's map
        (``associate``), start new landmarks in free slots for readings outside ``settings.new_gate_prob``'s gate
        of every landmark, correct with the rest as ``correct`` does, and forget a new landmark not matched again
        within ``settings.confirm_steps`` of the calls for the robot that started it (0: never; a reading by any
        robot confirms it). Returns an ``UnknownCorrection`` (slots used, which were new, slots forgotten, change of log det
        Sigma)."""
        code, gates, new_threshold, _, _ = self._association_options(settings)
        confirm_within = int(settings.confirm_steps)
        robot = self._robot(robot)
        readings = np.ascontiguousarray(np.asarray(readings, dtype=float).reshape(-1, 2))
        if not np.all(np.isfinite(readings)):
            raise ValueError("readings must be finite")
        Q = self._noise(measurement_cov, self.measurement_noise)
        m = len(readings)
        slots = np.empty(m, dtype=np.int64)
        nearest = np.empty(m)
        mean, cov = self._robot_view(robot)
        compiled.associate(
            mean, cov, self._observed, readings, Q, self.min_range, code, gates, association.MAX_NODES, slots,
            nearest,
        )  # fmt: skip
        new = np.zeros(m, dtype=bool)
        free = iter(np.flatnonzero(~self._observed).tolist())
        for i in np.flatnonzero((slots < 0) & (nearest > new_threshold)):
            slot = next(free, None)
            if slot is None:
                break
            slots[i], new[i] = slot, True
        use = slots >= 0
        delta = self.correct(robot, slots[use], readings[use], measurement_cov=Q)
        too_close = new & ~self._observed[np.maximum(slots, 0)]  # inverse mode: not initialised, not used
        slots[too_close], new[too_close] = -1, False
        self._tentative[slots[(slots >= 0) & ~new]] = 0
        counting = (self._tentative > 0) & (self._started_by == robot)
        self._tentative[counting] -= 1
        forgotten = np.flatnonzero(counting & (self._tentative == 0))
        if confirm_within > 0:
            self._tentative[slots[new]] = confirm_within
            self._started_by[slots[new]] = robot
        if len(forgotten):
            delta += self._forget(forgotten)
        return UnknownCorrection(slots, new, forgotten, delta)

    def forget(self, index: int) -> float:
        """Return landmark slot ``index`` to the unseen prior (as ``EKFSLAM.forget``); returns the change of
        log det Sigma (recomputed by ``resync``)."""
        if (
            isinstance(index, bool)
            or not isinstance(index, (int, np.integer))
            or not 0 <= index < self.n_landmarks
        ):
            raise IndexError(f"landmark index {index!r} outside [0, {self.n_landmarks})")
        return self._forget(np.array([index]))

    def _forget(self, slots: np.ndarray) -> float:
        for index in slots:
            j = self.landmark_index(int(index))
            self._cov[j : j + 2, :] = 0.0
            self._cov[:, j : j + 2] = 0.0
            self._cov[j, j] = self._cov[j + 1, j + 1] = self.landmark_prior
            self._mean[j : j + 2] = 0.0
        self._first[slots] = 0.0
        self._observed[slots] = False
        self._tentative[slots] = 0
        if not self._tracking:
            return 0.0
        before = self._log_det
        self.resync()
        return self._log_det - before

    def _robot_view(self, robot: int) -> tuple[np.ndarray, np.ndarray]:
        """Robot ``robot``'s pose and the map as a single-robot state (mean (3 + 2n,), cov): copies, O(size^2),
        what a correction costs anyway. With one robot, the state itself."""
        if self.n_robots == 1:
            return self._mean, self._cov
        o = 3 * robot
        index = np.r_[o : o + 3, 3 * self.n_robots : self.state_size]
        return self._mean[index], np.ascontiguousarray(self._cov[np.ix_(index, index)])

    # EKFSLAM's, on this filter's landmark count and cache: the same options for the same settings object.
    _association_options = EKFSLAM._association_options

    # ------------------------------------------------------------------ helpers
    def _robot(self, robot) -> int:
        if (
            isinstance(robot, bool)
            or not isinstance(robot, (int, np.integer))
            or not 0 <= robot < self.n_robots
        ):
            raise IndexError(f"robot index {robot!r} outside [0, {self.n_robots})")
        return int(robot)

    @staticmethod
    def _readings(readings, count: int) -> np.ndarray:
        out = np.asarray(readings, dtype=float).reshape(-1, 2) if count else np.empty((0, 2))
        if out.shape[0] != count:
            raise ValueError(f"{count} ids but {out.shape[0]} readings")
        return np.ascontiguousarray(out)

    @staticmethod
    def _noise(measurement_cov, default: np.ndarray) -> np.ndarray:
        if measurement_cov is None:
            return default
        return _as_covariance(measurement_cov, 2, "measurement_cov")

    @staticmethod
    def _raise_status(status: int) -> None:
        if status == codes.BAD_INPUT:
            raise ValueError("readings must be finite")
        if status == codes.NOT_PD:
            raise FilterDivergedError("innovation covariance is not positive definite")
        if status != codes.OK:
            raise RuntimeError(f"unknown correction status {status}")

    def _after_call(self, delta: float) -> None:
        if self._tracking:
            self._log_det += delta
            self._calls_since_resync += 1
            if self.resync_every and self._calls_since_resync >= self.resync_every:
                self.resync()
        else:
            self.resync()

    def resync(self) -> float:
        """Recompute log det Sigma and P from a Cholesky of Sigma (O(size^3)); returns the correction applied.
        While Sigma is singular log det stays -inf; a Sigma that loses definiteness after tracking started raises
        ``FilterDivergedError``."""
        try:
            chol = np.linalg.cholesky(self._cov)
        except np.linalg.LinAlgError:
            if self._tracking:
                raise FilterDivergedError("covariance is no longer positive definite") from None
            return 0.0
        log_det = 2.0 * float(np.sum(np.log(np.diagonal(chol))))
        pose_size = 3 * self.n_robots
        unit = np.zeros((self._cov.shape[0], pose_size))
        unit[:pose_size, :pose_size] = np.eye(pose_size)
        x = np.linalg.solve(chol, unit)
        info = x.T @ x
        self._P[:, :] = np.linalg.inv(0.5 * (info + info.T))
        drift = log_det - self._log_det if self._tracking else 0.0
        self._log_det = log_det
        self._tracking = True
        self._calls_since_resync = 0
        return drift
