"""The filter's settings: one frozen, validated object with one set of defaults, for ``EKFSLAM`` and the env.

Each choice is defined here once (the names a setting takes and their meaning); ``EKFSLAM``, the env's
``filter`` section, the command lines and the benchmarks read them from here. The defaults are the env's (the
wheels model, inverse initialisation, a 100 m^2 landmark prior, a 1e-10 pose prior); ``COURSE_SETTINGS``
holds the course's (the odometry model, course initialisation, a 1000 m^2 landmark prior, a zero pose
prior), which its replay (``ekfslam_gym.evaluation.replay``) uses.

Loads neither numba nor the kernels: registering the env ids and validating a config stay cheap.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any, Literal, get_args

from .association import DEFAULT_GATE, DEFAULT_NEW_GATE

MotionModel = Literal["wheels", "odometry", "velocity"]
Variant = Literal["ekf", "fej", "iekf"]
InitMode = Literal["inverse", "course"]
UpdateMode = Literal["batch", "sequential"]
Association = Literal["known", "nearest", "jcbc"]

MOTION_MODELS: tuple[str, ...] = get_args(MotionModel)
VARIANTS: tuple[str, ...] = get_args(Variant)
INIT_MODES: tuple[str, ...] = get_args(InitMode)
UPDATE_MODES: tuple[str, ...] = get_args(UpdateMode)
ASSOCIATIONS: tuple[str, ...] = get_args(Association)


def _check(condition: bool, name: str, message: str, value: Any) -> None:
    if not condition:
        raise ValueError(f"filter.{name} {message}, got {value!r}")


def _choice(name: str, value: Any, choices: tuple[str, ...]) -> None:
    _check(value in choices, name, f"must be {'|'.join(choices)}", value)


def _number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def _integer(name: str, value: Any, minimum: int) -> None:
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= minimum
    _check(ok, name, f"must be an integer >= {minimum}", value)


@dataclass(frozen=True)
class FilterSettings:
    """How the EKF-SLAM filters: its motion model, linearisation, landmark initialisation, priors and data
    association. The sensor's and odometer's noise are not settings: they come with the readings.

    motion_model: ``wheels`` (wheel travels (left, right) and a sideways slip, which reads a slide along a
    wall as a slip rather than as large turns; the simulator's ``WheelOdometryNoise``), ``odometry``
    (turn-drive-turn with Thrun's alpha noise, the course's model) or ``velocity`` (v, omega for ``dt`` s).
    variant: where the filter linearises: ``ekf`` (at the estimate), ``fej`` (first-estimates Jacobians,
    Huang, Mourikis & Roumeliotis 2010: no spurious information about the unobservable global pose) or
    ``iekf`` (the correction iterated by Gauss-Newton, at most ``iterations`` linearisations); all keep the
    exact running log det.
    init_mode: ``inverse`` (a landmark's first reading sets its mean and covariance through the inverse
    sensor model and is not used again; the standard for a simulated robot) or ``course`` (the first reading
    sets the mean, the prior covariance stays, and the reading is then used in the update).
    update: ``batch`` (a step's readings in one update) or ``sequential`` (one at a time, relinearising).
    landmark_prior: variance (m^2) at which every unseen landmark is carried, so log det Sigma is finite and
    discovering a landmark pays a bounded amount. pose_prior: the initial pose variance (m^2 and rad^2) on each
    of x, y, theta; 0 (the course's) leaves Sigma singular, log det -inf, until the first prediction.
    resync_every: filter calls between exact Cholesky re-synchronisations of the running log det (0: never).
    association: how readings find their landmarks: ``known`` (the sensor's ids), ``nearest`` (each reading
    alone takes its most likely landmark inside the gate) or ``jcbc`` (joint compatibility branch and bound,
    Neira & Tardos 2001), the latter two from the readings alone (``ekfslam_gym.filter.association``).
    gate_prob: probability of the chi-squared association gates. new_gate_prob (>= gate_prob): a reading that
    matches nothing and lies outside this gate of every landmark starts a new one in a free slot; between the
    gates it is discarded. confirm_steps: a new landmark not matched again within this many corrections is
    forgotten (its slot freed, so clutter does not fill the map; 0: never).
    """

    motion_model: str = "wheels"
    variant: str = "ekf"
    iterations: int = 5
    init_mode: str = "inverse"
    update: str = "batch"
    landmark_prior: float = 100.0
    pose_prior: float = 1e-10
    resync_every: int = 1000
    association: str = "known"
    gate_prob: float = DEFAULT_GATE
    new_gate_prob: float = DEFAULT_NEW_GATE
    confirm_steps: int = 5

    def __post_init__(self) -> None:
        _choice("motion_model", self.motion_model, MOTION_MODELS)
        _choice("variant", self.variant, VARIANTS)
        _integer("iterations", self.iterations, 1)
        _choice("init_mode", self.init_mode, INIT_MODES)
        _choice("update", self.update, UPDATE_MODES)
        _check(_number(self.landmark_prior) and self.landmark_prior > 0, "landmark_prior", "must be > 0",
               self.landmark_prior)  # fmt: skip
        _check(
            _number(self.pose_prior) and self.pose_prior >= 0, "pose_prior", "must be >= 0", self.pose_prior
        )
        _integer("resync_every", self.resync_every, 0)
        _choice("association", self.association, ASSOCIATIONS)
        for name in ("gate_prob", "new_gate_prob"):
            value = getattr(self, name)
            _check(_number(value) and 0.0 < value < 1.0, name, "must be in (0, 1)", value)
        _integer("confirm_steps", self.confirm_steps, 0)
        _check(self.new_gate_prob >= self.gate_prob, "new_gate_prob", "must be >= filter.gate_prob",
               self.new_gate_prob)  # fmt: skip


# The course's filter (its replay and its figures): odometry model, course initialisation, landmarks at
# 1000 m^2, the pose known exactly at the start.
COURSE_SETTINGS = FilterSettings(
    motion_model="odometry", init_mode="course", landmark_prior=1000.0, pose_prior=0.0
)
