"""EKF-SLAM with known correspondences, a fixed number of landmarks and an exact running log det Sigma.

The state is mu = (x, y, theta, m1x, m1y, ..., mnx, mny), N = 3 + 2n, with covariance Sigma. The heavy lifting
is in ``kernels`` (compiled, touching only what changes); this class validates input, holds the state and
keeps the log-determinant bookkeeping honest (start it from a Cholesky once Sigma is definite, re-synchronise
every ``resync_every`` filter calls to bound rounding drift).
"""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Any, NamedTuple

import numpy as np

from .. import compiled
from ..angles import wrap_angle
from . import association, codes
from .association import UnknownCorrection
from .settings import AssociationSettings, FilterSettings

_FLOAT64 = np.dtype(np.float64)
_INT64 = np.dtype(np.int64)

COURSE_MOTION_NOISE = np.diag([0.1, 0.1, 0.01])
COURSE_MEASUREMENT_NOISE = 0.01 * np.eye(2)

_MODEL_CODES = {
    "odometry": codes.MODEL_ODOMETRY,
    "velocity": codes.MODEL_VELOCITY,
    "wheels": codes.MODEL_WHEELS,
}
_CONTROL_WIDTH = {"odometry": 3, "velocity": 2, "wheels": 3}
_VARIANT_CODES = {"ekf": codes.VARIANT_EKF, "fej": codes.VARIANT_FEJ, "iekf": codes.VARIANT_IEKF}


class Jacobians(NamedTuple):
    """The Jacobians the filter last linearised with, as its variant chose them (for observability analysis).

    motion: G (3, 3) of the last prediction. slots (k,): the landmarks of the k readings used by the last
    correction, in the order used; measurement (k, 2, 5): d reading / d (x, y, theta, landmark x, landmark y)
    for each. Copies.
    """

    motion: np.ndarray
    slots: np.ndarray
    measurement: np.ndarray


class FilterDivergedError(RuntimeError):
    """The filter's covariance lost positive definiteness (an innovation covariance or Sigma itself)."""


_SETTING_NAMES = tuple(f.name for f in dataclasses.fields(FilterSettings))


def _settings(settings: FilterSettings | None, changes: dict[str, Any]) -> FilterSettings:
    """``settings`` (default ``FilterSettings()``) with ``changes`` to its fields, validated: a plain
    ``FilterSettings`` (a subclass, such as the env's section, gives its filter fields and nothing more)."""
    if settings is None:
        settings = FilterSettings()
    elif not isinstance(settings, FilterSettings):
        raise TypeError(f"settings must be a FilterSettings, got {type(settings).__name__}")
    elif type(settings) is not FilterSettings:
        settings = FilterSettings(**{name: getattr(settings, name) for name in _SETTING_NAMES})
    if not changes:
        return settings
    unknown = sorted(set(changes) - set(_SETTING_NAMES))
    if unknown:
        raise TypeError(f"unknown filter setting(s) {unknown}; known: {list(_SETTING_NAMES)}")
    return dataclasses.replace(settings, **changes)


def _as_covariance(value, size: int, name: str) -> np.ndarray:
    """Accept a scalar variance, a diagonal of variances or a full matrix; check it is symmetric PD."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = float(arr) * np.eye(size)
    elif arr.shape == (size,):
        arr = np.diag(arr)
    elif arr.shape != (size, size):
        raise ValueError(
            f"{name} must be a scalar, a ({size},) diagonal or a ({size}, {size}) matrix, got {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    # numpy.allclose's test (rtol 1e-5, atol 1e-8) written out: a tenth of its cost, paid at every env reset
    if not np.all(np.abs(arr - arr.T) <= 1e-8 + 1e-5 * np.abs(arr.T)):
        raise ValueError(f"{name} must be symmetric")
    return np.ascontiguousarray(0.5 * (arr + arr.T))


def _check_positive_definite(arr: np.ndarray, name: str) -> None:
    if np.any(np.linalg.eigvalsh(arr) <= 0):
        raise ValueError(f"{name} must be positive definite")


def _motion_inputs(
    control, motion_model: str, width: int, motion_cov, control_cov, motion_noise: np.ndarray
) -> tuple[np.ndarray, np.ndarray, bool]:
    """A prediction's (control, noise, noise in control space) as ``EKFSLAM.predict`` takes them, checked: the
    control has the model's ``width`` numbers; ``control_cov`` (width x width) wins over ``motion_cov`` (3 x 3,
    pose space), and neither means ``motion_noise``. Shared by ``EKFSLAM`` and ``TeamEKF``."""
    control = np.asarray(control, dtype=float)
    if control.shape != (width,):
        raise ValueError(f"control must be {width} numbers for the {motion_model} model, got {control!r}")
    if control_cov is not None:
        noise = np.asarray(control_cov, dtype=float)
        if noise.shape != (width, width):
            raise ValueError(f"control_cov must be ({width}, {width}), got {noise.shape}")
        return control, noise, True
    noise = motion_noise if motion_cov is None else np.asarray(motion_cov, dtype=float)
    if noise.shape != (3, 3):
        raise ValueError(f"motion_cov must be (3, 3), got {noise.shape}")
    return control, noise, False


class EKFSLAM:
    """EKF-SLAM for ``n_landmarks`` point landmarks observed by a range-bearing sensor.

    ``EKFSLAM(n)`` filters as the env does (``FilterSettings()``: the wheels model, inverse initialisation);
    ``EKFSLAM(n, COURSE_SETTINGS)`` as the course does; ``EKFSLAM(n, variant="fej")`` changes one setting
    of the defaults, ``EKFSLAM(n, settings, variant="fej")`` one of ``settings``.

    Args:
        n_landmarks: number of landmark slots (fixed; readings name them by 0-based index).
        settings: how it filters (``ekfslam_gym.filter.settings.FilterSettings``, whose docstring explains
            each field; default ``FilterSettings()``). How readings find their landmarks is not the
            filter's setting but each call's: ``associate`` and ``correct_unknown`` take an
            ``AssociationSettings``.
        dt: control period in seconds for the velocity model.
        wheel_base: metres between the wheels, for the wheels model (the odometer's, e.g.
            ``WheelOdometryNoise.wheel_base``).
        motion_noise: R, the pose-space noise added at every prediction (3x3, a (3,) diagonal or a scalar);
            default the course's diag(0.1, 0.1, 0.01). ``predict`` can override it per step, in pose space or
            in control space (R = V M V^T).
        measurement_noise: Q, the covariance of one (range, bearing) reading; default the course's 0.01 I.
        initial_pose: the pose mean at time 0 (default the origin).
        initial_pose_cov: the pose covariance at time 0 (scalar, (3,) diagonal or 3x3) where it is not
            ``settings.pose_prior`` times the identity (e.g. a heading less certain than the position).
        min_range: metres; below it the range-bearing Jacobian uses this range instead of dividing by ~0, and a
            reading this close never initialises a landmark in inverse mode.
        **changes: fields of ``FilterSettings`` to change from ``settings``.

    Controls: (rot1, trans, rot2) for the ``odometry`` model (Thrun et al. table 5.6), (v, omega) applied
    for ``dt`` seconds for ``velocity`` (table 5.3), (left, right, slip) wheel travels and a sideways slip in
    metres for ``wheels`` (``models.wheel_motion``). Every variant keeps the exact running log det and the
    O(m N^2) correction: ``ekf`` takes the Jacobians at the current estimate; ``fej`` (first-estimates
    Jacobians, Huang, Mourikis & Roumeliotis, "Observability-based rules for designing consistent EKF SLAM
    estimators", IJRR 2010) the measurement Jacobians at the pose's prediction and each landmark's first
    estimate, the motion Jacobian from the previous prediction, so the linearised system keeps the three
    unobservable directions of planar SLAM (global x, y, rotation) instead of gaining spurious information
    about the rotation; ``iekf`` relinearises the correction by Gauss-Newton up to ``iterations`` times (Bell
    & Cathey 1993), the covariance updated once at the end. A landmark prior is bounded on purpose: an
    infinite prior makes log det Sigma meaningless.
    """

    def __init__(
        self,
        n_landmarks: int,
        settings: FilterSettings | None = None,
        *,
        dt: float = 0.1,
        wheel_base: float = 0.3,
        motion_noise=COURSE_MOTION_NOISE,
        measurement_noise=COURSE_MEASUREMENT_NOISE,
        initial_pose=None,
        initial_pose_cov=None,
        min_range: float = 1e-3,
        **changes: Any,
    ) -> None:
        settings = _settings(settings, changes)
        if isinstance(n_landmarks, bool) or not isinstance(n_landmarks, (int, np.integer)) or n_landmarks < 0:
            raise ValueError(f"n_landmarks must be a non-negative integer, got {n_landmarks!r}")
        if not (np.isfinite(wheel_base) and wheel_base > 0):
            raise ValueError(f"wheel_base must be a positive number of metres, got {wheel_base!r}")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
        if not (np.isfinite(min_range) and min_range > 0):
            raise ValueError(f"min_range must be positive, got {min_range!r}")

        self.settings = settings
        self.n_landmarks = int(n_landmarks)
        self.motion_model = settings.motion_model
        self.dt = float(dt)
        self.wheel_base = float(wheel_base)
        self.variant = settings.variant
        self.iterations = settings.iterations
        self.init_mode = settings.init_mode
        self.update_mode = settings.update
        self.min_range = float(min_range)
        self.resync_every = settings.resync_every
        self.landmark_prior = float(settings.landmark_prior)
        self.motion_noise = _as_covariance(motion_noise, 3, "motion_noise")
        self.measurement_noise = _as_covariance(measurement_noise, 2, "measurement_noise")
        _check_positive_definite(self.measurement_noise, "measurement_noise")
        pose_cov0 = _as_covariance(
            settings.pose_prior if initial_pose_cov is None else initial_pose_cov, 3, "initial_pose_cov"
        )

        size = 3 + 2 * self.n_landmarks
        self._mean = np.zeros(size)
        if initial_pose is not None:
            pose = np.asarray(initial_pose, dtype=float)
            if pose.shape != (3,) or not np.all(np.isfinite(pose)):
                raise ValueError(f"initial_pose must be 3 finite numbers, got {initial_pose!r}")
            self._mean[:3] = pose
            self._mean[2] = wrap_angle(pose[2])
        self._cov = np.zeros((size, size))
        self._cov[:3, :3] = pose_cov0
        idx = np.arange(3, size)
        self._cov[idx, idx] = self.landmark_prior
        self._observed = np.zeros(self.n_landmarks, dtype=bool)
        self._width = _CONTROL_WIDTH[self.motion_model]
        # First estimates: the pose as the last prediction left it, each landmark as it was initialised.
        self._prior_pose = self._mean[:3].copy()
        self._first = np.zeros((self.n_landmarks, 2))
        # correct_unknown's tentative landmarks: corrections left to be matched again before being forgotten.
        self._tentative = np.zeros(self.n_landmarks, dtype=np.int64)
        self._association_cache: dict = {}
        # The Jacobians last used (see ``Jacobians``), written by the kernels.
        self._G_used = np.eye(3)
        self._H_used = np.zeros((max(16, self.n_landmarks), 2, 5))
        self._H_slots = np.zeros(self._H_used.shape[0], dtype=np.int64)
        self._n_used = 0
        self._control = np.zeros(3)
        self._P = np.zeros((3, 3))
        self._log_det = -np.inf
        self._tracking = False
        self._calls_since_resync = 0
        # What the kernels take (``kernels.FilterArrays`` and ``FilterOptions``), built once.
        self._arrays = self._kernel_arrays()
        self._options = (
            _MODEL_CODES[self.motion_model], self.dt, self.wheel_base, self.min_range, self.init_mode == "course",
            self.update_mode == "sequential", _VARIANT_CODES[self.variant], int(self.iterations),
        )  # fmt: skip
        self._start_tracking(pose_cov0)

    def _kernel_arrays(self) -> tuple[np.ndarray, ...]:
        return (
            self._mean, self._cov, self._P, self._observed, self._prior_pose, self._first, self._G_used,
            self._H_used, self._H_slots,
        )  # fmt: skip

    def _start_tracking(self, pose_cov0: np.ndarray) -> None:
        """``resync()`` for the initial, block-diagonal Sigma = diag(pose prior, landmark prior I) in O(1):
        log det Sigma = log det(pose prior) + 2n log(landmark prior) and P = the pose prior. A singular pose
        prior (the course's zero) leaves tracking to the first ``resync`` after a prediction, as ``resync`` does.
        """
        try:
            chol = np.linalg.cholesky(pose_cov0)
        except np.linalg.LinAlgError:
            return
        self._log_det = 2.0 * float(np.sum(np.log(np.diagonal(chol)))) + 2 * self.n_landmarks * math.log(
            self.landmark_prior
        )
        self._P[:, :] = pose_cov0
        self._tracking = True

    # ------------------------------------------------------------------ state
    @property
    def state_size(self) -> int:
        return self._mean.shape[0]

    @property
    def mean(self) -> np.ndarray:
        """The full state mean (N,), read-only view."""
        return _read_only(self._mean)

    @property
    def cov(self) -> np.ndarray:
        """The full covariance Sigma (N, N), read-only view."""
        return _read_only(self._cov)

    @property
    def pose(self) -> np.ndarray:
        return _read_only(self._mean[:3])

    @property
    def pose_cov(self) -> np.ndarray:
        """Marginal pose covariance Sigma_xx (3, 3)."""
        return _read_only(self._cov[:3, :3])

    @property
    def landmarks(self) -> np.ndarray:
        """Landmark means (n, 2); unseen ones hold 0 until initialised."""
        return _read_only(self._mean[3:].reshape(-1, 2))

    @property
    def observed(self) -> np.ndarray:
        """Which landmarks have been initialised (n,) bool."""
        return _read_only(self._observed)

    @property
    def log_det(self) -> float:
        """log det Sigma, kept incrementally; -inf while Sigma is singular (the course's zero pose prior)."""
        return self._log_det

    @property
    def pose_cov_given_map(self) -> np.ndarray:
        """P, the pose covariance conditioned on the map (Schur complement of the map block); zeros until
        Sigma is definite. log det Sigma = log det Sigma_mm + log det P."""
        return _read_only(self._P)

    def landmark_cov(self, index: int) -> np.ndarray:
        """Marginal covariance (2, 2) of landmark ``index`` (0-based)."""
        if not 0 <= index < self.n_landmarks:
            raise IndexError(f"landmark index {index} outside [0, {self.n_landmarks})")
        j = 3 + 2 * index
        return self._cov[j : j + 2, j : j + 2].copy()

    def landmark_covs(self) -> np.ndarray:
        """Marginal covariances of all landmarks (n, 2, 2), a copy."""
        diag = np.diagonal(self._cov)[3:]
        out = np.empty((self.n_landmarks, 2, 2))
        out[:, 0, 0] = diag[0::2]
        out[:, 1, 1] = diag[1::2]
        off = self._cov[3::2, 4::2].diagonal() if self.n_landmarks else np.empty(0)
        out[:, 0, 1] = off
        out[:, 1, 0] = off
        return out

    @property
    def last_jacobians(self) -> Jacobians:
        """The Jacobians of the last prediction and correction, as this variant took them."""
        k = self._n_used
        return Jacobians(self._G_used.copy(), self._H_slots[:k].copy(), self._H_used[:k].copy())

    def copy(self) -> EKFSLAM:
        """An independent copy (for planners that simulate the filter forward)."""
        return copy.deepcopy(self)

    # ------------------------------------------------------------------ filter
    def predict(self, control, *, motion_cov=None, control_cov=None) -> float:
        """Prediction with the motion model; returns the change of log det Sigma.

        ``control`` is (rot1, trans, rot2) for the odometry model, (v, omega) for the velocity model or
        (left, right, slip) for the wheels model. Noise: ``motion_cov`` (pose space, 3x3) or ``control_cov``
        (control space: 3x3 odometry and wheels, 2x2 velocity, mapped through V M V^T); neither means the
        constructor's ``motion_noise``.
        """
        control, noise, in_control_space = _motion_inputs(
            control, self.motion_model, self._width, motion_cov, control_cov, self.motion_noise
        )
        self._control[: self._width] = control
        delta, status = compiled.predict(
            self._arrays,
            self._options,
            self._control,
            np.ascontiguousarray(noise),
            in_control_space,
            self._tracking,
        )
        if status == codes.BAD_INPUT:
            raise ValueError(f"control and its noise must be finite, got {control!r}")
        self._after_call(delta)
        return delta

    def correct(self, ids, readings, *, measurement_cov=None) -> float:
        """Correction with range-bearing readings (known correspondences); returns the change of log det Sigma.

        ``ids`` (m,) are 0-based landmark slots, ``readings`` (m, 2) are (range m, bearing rad). Raw bearings
        need not be wrapped: the innovation is. Raises ``FilterDivergedError`` if an innovation covariance is
        not positive definite: a batch update then changes nothing, a sequential one keeps the readings it
        applied before the one that failed, and ``log_det`` counts them (``_fail``).
        """
        ids = np.ascontiguousarray(np.asarray(ids, dtype=np.int64).reshape(-1))
        readings = np.asarray(readings, dtype=float).reshape(-1, 2) if len(ids) else np.empty((0, 2))
        if readings.shape[0] != ids.shape[0]:
            raise ValueError(f"{ids.shape[0]} ids but {readings.shape[0]} readings")
        Q = self._noise(measurement_cov)
        self._reserve_jacobians(ids.shape[0])
        delta, status, used = compiled.correct(
            self._arrays, self._options, ids, np.ascontiguousarray(readings), Q, self._tracking
        )
        self._n_used = used
        if status != codes.OK:
            self._fail(status, delta, ids)
        self._after_call(delta)
        return delta

    def _reserve_jacobians(self, readings: int) -> None:
        """Room for the Jacobians of ``readings`` readings (``last_jacobians``), grown when a step has more."""
        if readings > self._H_slots.shape[0]:
            self._H_used = np.zeros((2 * readings, 2, 5))
            self._H_slots = np.zeros(2 * readings, dtype=np.int64)
            self._arrays = self._kernel_arrays()

    def _fail(self, status: int, applied: float, ids: np.ndarray) -> None:
        """Raise for a correction's failure ``status`` after counting ``applied``, the change of log det Sigma of
        what the kernel applied before it failed, so that ``log_det`` stays log det ``cov``.

        Only a sequential correction applies anything before failing (its earlier readings, and inverse
        initialisations); bad ids and readings are found before anything moves, and a failed batch update
        is undone by the kernel. The readings applied are kept rather than rolled back: each was a complete
        correction (sequential updating is a sequence of one-reading corrections, and the one that failed
        changed nothing), so the state is the filter after the readings before it, a valid belief; undoing
        them would cost a copy of Sigma, O(N^2), at every sequential call to serve a failure that ends the
        env's episode.
        """
        if applied != 0.0:
            self._after_call(applied)
        self._raise_correction_status(status, ids)

    def _raise_correction_status(self, status: int, ids: np.ndarray) -> None:
        if status == codes.BAD_ID:
            raise ValueError(f"landmark ids must lie in [0, {self.n_landmarks}), got {ids.tolist()}")
        if status == codes.BAD_INPUT:
            raise ValueError("readings must be finite")
        if status == codes.NOT_PD:
            raise FilterDivergedError("innovation covariance is not positive definite")
        raise RuntimeError(f"unknown correction status {status}")

    def update(
        self, control: np.ndarray, control_cov: np.ndarray, ids: np.ndarray, readings: np.ndarray
    ) -> float:
        """``predict(control, control_cov=control_cov)`` then ``correct(ids, readings)``, for the env's hot path:
        the same kernels and results, without converting the arrays. They must already be what the simulator
        hands out: float64 ``control`` (width,) and C-contiguous ``control_cov`` (width, width), int64 ``ids``
        (m,), C-contiguous float64 ``readings`` (m, 2); anything else raises ``TypeError``. The kernels still
        check values: a bad id or reading raises after the prediction. Returns the change of log det Sigma."""
        width = self._width
        if not (  # dtypes by identity: the native float64 and int64 are singletons (and 4x cheaper to test)
            control.shape == (width,)
            and control_cov.shape == (width, width)
            and control.dtype is _FLOAT64
            and control_cov.dtype is _FLOAT64
            and control_cov.flags.c_contiguous
            and ids.dtype is _INT64
            and readings.dtype is _FLOAT64
            and readings.shape == (ids.shape[0], 2)
            and ids.flags.c_contiguous
            and readings.flags.c_contiguous
        ):
            raise TypeError("update() takes the simulator's arrays as they are; use predict() and correct()")
        if width == 3:
            kernel_control = control  # as the kernel reads it: no copy
        else:  # (v, omega): the kernel reads three entries
            kernel_control = self._control
            kernel_control[:width] = control
        if ids.shape[0] > self._H_slots.shape[0]:
            self._reserve_jacobians(ids.shape[0])
        if not self._tracking or (self.resync_every and self._calls_since_resync + 1 >= self.resync_every):
            # a resync falls between the two (or tracking starts): the calls one at a time, as the library's
            return self.predict(control, control_cov=control_cov) + self.correct(ids, readings)
        delta, status, change, correction_status, self._n_used = compiled.predict_correct(
            self._arrays, self._options, kernel_control, control_cov, ids, readings, self.measurement_noise
        )
        if status == codes.BAD_INPUT:
            raise ValueError(f"control and its noise must be finite, got {control!r}")
        # Both calls' bookkeeping (``_after_call`` twice): tracking, and no resync after the first (checked above).
        # A failed correction's ``change`` is what it applied before failing (``_fail``), counted all the same.
        self._log_det += delta
        self._log_det += change  # two additions, as two calls make them (the same rounding)
        self._calls_since_resync += 2
        if correction_status != codes.OK:
            self._raise_correction_status(correction_status, ids)
        if self.resync_every and self._calls_since_resync >= self.resync_every:
            self.resync()
        return delta + change

    # ------------------------------------------------------------------ unknown correspondences
    def associate(self, readings, settings: AssociationSettings, *, measurement_cov=None) -> np.ndarray:
        """The initialised landmark slot each reading (m, 2) comes from, -1 for none (new, clutter or ambiguous).

        ``settings.kind``: ``"nearest"`` (each reading alone takes its most likely landmark inside the gate) or
        ``"jcbc"`` (joint compatibility branch and bound, Neira & Tardos 2001: the most pairings whose stacked
        innovation passes the joint test); ``settings.gate_prob``: the probability of the chi-squared gates
        (2k degrees of freedom for k pairings). Changes nothing.
        """
        code, gates, _, max_nodes, _ = self._association_options(settings)
        readings = self._readings(readings)
        if not np.all(np.isfinite(readings)):
            raise ValueError("readings must be finite")
        m = readings.shape[0]
        slots = np.empty(m, dtype=np.int64)
        compiled.associate(
            self._mean, self._cov, self._observed, readings, self._noise(measurement_cov), self.min_range, code,
            gates, max_nodes, slots, np.empty(m),
        )  # fmt: skip
        return slots

    def correct_unknown(
        self, readings, settings: AssociationSettings, *, measurement_cov=None
    ) -> UnknownCorrection:
        """Associate the readings (m, 2) as ``associate`` does, then correct with the matched ones as ``correct``
        does, initialising new landmarks: a reading that matches nothing and lies outside the
        ``settings.new_gate_prob`` chi-squared gate (2 dof) of every initialised landmark starts one in the first
        free slot (none left: discarded); readings between the two gates are discarded, being neither clearly
        known nor clearly new.

        ``settings.confirm_steps`` > 0 makes a new landmark tentative: unless one of the next ``confirm_steps``
        calls matches a reading to it, it is forgotten (``forget``), so clutter does not fill the fixed-size
        state (a simple form of the provisional landmark list of Thrun, Burgard & Fox, sec. 10.3.3). Returns an
        ``UnknownCorrection`` (slots used, which were new, slots forgotten, change of log det Sigma).
        """
        options = self._association_options(settings)
        readings = self._readings(readings)
        m = readings.shape[0]
        self._reserve_jacobians(m)
        slots = np.empty(m, dtype=np.int64)
        new = np.empty(m, dtype=bool)
        forget = np.empty(self.n_landmarks, dtype=np.int64)
        delta, status, used, n_forget = compiled.correct_unknown(
            self._arrays, self._options, readings, self._noise(measurement_cov), self._tracking, options,
            self._tentative, slots, new, forget,
        )  # fmt: skip
        self._n_used = used
        if status != codes.OK:
            self._fail(status, delta, slots)
        self._after_call(delta)
        forgotten = forget[:n_forget]
        if n_forget:
            delta += self._forget(forgotten)
        return UnknownCorrection(slots, new, forgotten, delta)

    def forget(self, index: int) -> float:
        """Return landmark slot ``index`` to the unseen prior (mean 0, variance ``landmark_prior``, no
        correlations), free for a new landmark; returns the change of log det Sigma.

        Marginalising a landmark out of a Gaussian drops its rows and columns; putting the independent prior
        back keeps the state's size. log det Sigma and P are then recomputed exactly (``resync``, O(N^3)): it
        happens only when a tentative landmark is dropped.
        """
        if (
            isinstance(index, bool)
            or not isinstance(index, (int, np.integer))
            or not 0 <= index < self.n_landmarks
        ):
            raise IndexError(f"landmark index {index!r} outside [0, {self.n_landmarks})")
        return self._forget(np.array([index]))

    def _forget(self, slots: np.ndarray) -> float:
        for index in slots:
            j = 3 + 2 * int(index)
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

    def _association_options(self, settings: AssociationSettings) -> tuple[int, np.ndarray, float, int, int]:
        """What the association kernels take (``association_kernels.AssociationOptions``): (method code, joint
        gates chi2(2k, gate_prob) for k = 1..n, new-landmark threshold chi2(2, new_gate_prob), JCBC's node
        budget, confirm_steps), computed once per settings object (validated when it was built)."""
        if not isinstance(settings, AssociationSettings):
            raise TypeError(f"settings must be an AssociationSettings, got {type(settings).__name__}")
        found = self._association_cache.get(settings)
        if found is None:
            code = association.check_method(settings.kind)
            gates = association.gate_table(settings.gate_prob, self.n_landmarks)
            new_threshold = association.chi2_even_ppf(settings.new_gate_prob, 2)
            found = (code, gates, new_threshold, association.MAX_NODES, int(settings.confirm_steps))
            self._association_cache[settings] = found
        return found

    @staticmethod
    def _readings(readings) -> np.ndarray:
        return np.ascontiguousarray(np.asarray(readings, dtype=float).reshape(-1, 2))

    def _noise(self, measurement_cov) -> np.ndarray:
        if measurement_cov is None:
            return self.measurement_noise
        return _as_covariance(measurement_cov, 2, "measurement_cov")

    def _after_call(self, delta: float) -> None:
        if self._tracking:
            self._log_det += delta
            self._calls_since_resync += 1
            if self.resync_every and self._calls_since_resync >= self.resync_every:
                self.resync()
        else:
            self.resync()

    def resync(self) -> float:
        """Recompute log det Sigma and P from a Cholesky of Sigma (O(N^3)); returns the correction applied.

        While Sigma is singular (only the course's zero pose prior before the first prediction) log det stays
        -inf and tracking waits; a Sigma that loses definiteness after that raises ``FilterDivergedError``.
        """
        try:
            chol = np.linalg.cholesky(self._cov)
        except np.linalg.LinAlgError:
            if self._tracking:
                raise FilterDivergedError("covariance is no longer positive definite") from None
            return 0.0
        log_det = 2.0 * float(np.sum(np.log(np.diagonal(chol))))
        # P^-1 is the pose block of Sigma^-1 = L^-T L^-1, i.e. X^T X with X = L^-1 E (E the pose columns).
        unit = np.zeros((self._cov.shape[0], 3))
        unit[:3, :3] = np.eye(3)
        x = np.linalg.solve(chol, unit)
        info = x.T @ x
        self._P[:, :] = np.linalg.inv(0.5 * (info + info.T))
        drift = log_det - self._log_det if self._tracking else 0.0
        self._log_det = log_det
        self._tracking = True
        self._calls_since_resync = 0
        return drift


def _read_only(arr: np.ndarray) -> np.ndarray:
    view = arr.view()
    view.flags.writeable = False
    return view
