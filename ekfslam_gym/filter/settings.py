"""The filter's settings, one frozen, validated object each, with one set of defaults.

``FilterSettings`` is how ``EKFSLAM`` filters (every field is one it reads); ``AssociationSettings`` is how
``EKFSLAM.associate`` and ``EKFSLAM.correct_unknown`` find the landmark each reading comes from when the
sensor's ids are not used. Each choice (the names a setting takes and their meaning) and each shared value is
defined here once; the env's ``filter`` section (``ekfslam_gym.envs.config.FilterConfig``), the replays, the
command lines and the benchmarks read them from here. The defaults are the env's (the wheels model, inverse
initialisation, a 100 m^2 landmark prior, ``KNOWN_START_POSE_PRIOR``); ``COURSE_SETTINGS`` holds the course's
(the odometry model, course initialisation, a 1000 m^2 landmark prior, a zero pose prior), which its replay
(``ekfslam_gym.replay.course``) uses.

Loads neither numba nor the kernels: registering the env ids and validating a config stay cheap.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal, get_args

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

# The pose prior (m^2 and rad^2 on x, y, theta) of a filter that starts where the robot truly is, to 10
# micrometres: Sigma is definite (log det finite) from the start. The env's default and the replays'.
KNOWN_START_POSE_PRIOR = 1e-10
# The env's landmark prior (m^2): bounded, so discovering a landmark pays a bounded amount of log det.
LANDMARK_PRIOR = 100.0
# The course's: its landmarks at 1000 m^2, its pose known exactly (Sigma singular until the first prediction).
COURSE_LANDMARK_PRIOR = 1000.0
COURSE_POSE_PRIOR = 0.0
# The association gates' probabilities and the tentative landmarks' lifetime (``AssociationSettings``).
GATE_PROB = 0.99
NEW_GATE_PROB = 0.999
CONFIRM_STEPS = 5


def _check(condition: bool, name: str, message: str, value: Any) -> None:
    if not condition:
        raise ValueError(f"{name} {message}, got {value!r}")


def _choice(name: str, value: Any, choices: tuple[str, ...]) -> None:
    _check(value in choices, name, f"must be {'|'.join(choices)}", value)


def _number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def _integer(name: str, value: Any, minimum: int) -> None:
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= minimum
    _check(ok, name, f"must be an integer >= {minimum}", value)


@dataclass(frozen=True)
class FilterSettings:
    """How the EKF-SLAM filters: its motion model, linearisation, landmark initialisation and priors. The
    sensor's and odometer's noise are not settings: they come with the readings.

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

    Errors name the field as the env's config does (``filter.variant must be ekf|fej|iekf, got 'ukf'``).
    """

    motion_model: str = "wheels"
    variant: str = "ekf"
    iterations: int = 5
    init_mode: str = "inverse"
    update: str = "batch"
    landmark_prior: float = LANDMARK_PRIOR
    pose_prior: float = KNOWN_START_POSE_PRIOR
    resync_every: int = 1000

    def __post_init__(self) -> None:
        _choice("filter.motion_model", self.motion_model, MOTION_MODELS)
        _choice("filter.variant", self.variant, VARIANTS)
        _integer("filter.iterations", self.iterations, 1)
        _choice("filter.init_mode", self.init_mode, INIT_MODES)
        _choice("filter.update", self.update, UPDATE_MODES)
        _check(_number(self.landmark_prior) and self.landmark_prior > 0, "filter.landmark_prior", "must be > 0",
               self.landmark_prior)  # fmt: skip
        _check(_number(self.pose_prior) and self.pose_prior >= 0, "filter.pose_prior", "must be >= 0",
               self.pose_prior)  # fmt: skip
        _integer("filter.resync_every", self.resync_every, 0)


# AssociationSettings' field -> the name its errors give; the env's section passes its own (``filter.*``).
ASSOCIATION_NAMES: Mapping[str, str] = {
    "kind": "association.kind",
    "gate_prob": "association.gate_prob",
    "new_gate_prob": "association.new_gate_prob",
    "confirm_steps": "association.confirm_steps",
}


def check_association(
    kind: Any,
    gate_prob: Any,
    new_gate_prob: Any,
    confirm_steps: Any,
    names: Mapping[str, str] = ASSOCIATION_NAMES,
) -> None:
    """Validate association settings, naming each field by ``names`` (``ValueError`` on the first bad one)."""
    _choice(names["kind"], kind, ASSOCIATIONS)
    for name, value in (("gate_prob", gate_prob), ("new_gate_prob", new_gate_prob)):
        _check(_number(value) and 0.0 < value < 1.0, names[name], "must be in (0, 1)", value)
    _integer(names["confirm_steps"], confirm_steps, 0)
    _check(
        new_gate_prob >= gate_prob, names["new_gate_prob"], f"must be >= {names['gate_prob']}", new_gate_prob
    )


@dataclass(frozen=True)
class AssociationSettings:
    """How readings find their landmarks when the sensor's ids are not used (``EKFSLAM.correct_unknown``).

    kind: ``known`` (the sensor's ids: nothing to associate; ``EKFSLAM.correct`` takes them), ``nearest``
    (each reading alone takes its most likely landmark inside the gate) or ``jcbc`` (joint compatibility
    branch and bound, Neira & Tardos 2001), the latter two from the readings alone
    (``ekfslam_gym.filter.association``). gate_prob: probability of the chi-squared association gates.
    new_gate_prob (>= gate_prob): a reading that matches nothing and lies outside this gate of every landmark
    starts a new one in a free slot; between the gates it is discarded. confirm_steps: a new landmark not
    matched again within this many corrections is forgotten (its slot freed, so clutter does not fill the
    map; 0: never).
    """

    kind: str = "known"
    gate_prob: float = GATE_PROB
    new_gate_prob: float = NEW_GATE_PROB
    confirm_steps: int = CONFIRM_STEPS

    def __post_init__(self) -> None:
        check_association(self.kind, self.gate_prob, self.new_gate_prob, self.confirm_steps)


# The course's filter (its replay and its figures): odometry model, course initialisation, landmarks at
# 1000 m^2, the pose known exactly at the start.
COURSE_SETTINGS = FilterSettings(
    motion_model="odometry",
    init_mode="course",
    landmark_prior=COURSE_LANDMARK_PRIOR,
    pose_prior=COURSE_POSE_PRIOR,
)
