"""The reward terms: pure functions of a control step's ``StepContext`` that return unweighted values.

``REWARD_TERMS`` is the one list of them: it makes ``RewardConfig``'s fields (the weights), the table in
``docs/environment.md`` and ``info["reward_terms"]``, which holds every term unweighted, whatever its weight, so
recorded steps can be re-weighted later. The reward is the weighted sum, taken in one place (``weigh``), over
the terms whose weight is non-zero. A new term is one function and one entry here.

The information gain is the D-optimality criterion of experimental design applied to the SLAM covariance (see
docs/filter-and-graph.md, *The maths, briefly*, and Carrillo, Reid & Castellanos, "On the comparison of uncertainty criteria
for active SLAM", ICRA 2012). It telescopes: it is the difference of one quantity from one control step to the
next, which ``Telescoped`` holds.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np


class Telescoped(NamedTuple):
    """The quantities the telescoping terms difference, as of one control step (or reset): log det Sigma of the
    filter's full covariance. Set at reset whatever the weights, so every term is reported from the first step
    on."""

    log_det: float


class StepContext(NamedTuple):
    """What one control step's reward terms read; nothing in it changes while they compute."""

    before: Telescoped  # at the previous control step (or reset)
    after: Telescoped  # after this control step's prediction and correction
    pose_cov: np.ndarray  # (3, 3) the pose block of Sigma after the step (m^2, rad^2)
    collided: bool  # the robot touched a wall during the step
    covered: float  # m^2 of the world the sensor looked at for the first time in this step


def info_gain(c: StepContext) -> float:
    return c.before.log_det - c.after.log_det


def collision(c: StepContext) -> float:
    return -1.0 if c.collided else -0.0


def step_cost(c: StepContext) -> float:
    return -1.0


def coverage(c: StepContext) -> float:
    return c.covered


def pose_variance(c: StepContext) -> float:
    return -(c.pose_cov.item(0, 0) + c.pose_cov.item(1, 1))  # item: Python floats, no numpy scalars


@dataclass(frozen=True)
class RewardTerm:
    """One reward term: its name (the ``reward`` config field and the ``reward_terms`` key), its default
    weight, what the weight multiplies and why a user would weigh it, and its function."""

    name: str
    default: float
    meaning: str
    value: Callable[[StepContext], float]


REWARD_TERMS: tuple[RewardTerm, ...] = (
    RewardTerm(
        "info_gain",
        1.0,
        "log det Sigma_{t-1} - log det Sigma_t, nats: the D-optimal information gain, the default reward; "
        "telescopes to log det Sigma_0 - log det Sigma_T",
        info_gain,
    ),
    RewardTerm("collision", 1.0, "-1 per control step in contact with a wall", collision),
    RewardTerm(
        "step_cost",
        0.0,
        "-1 per control step: with done_std, an episode that makes the map certain sooner ends sooner and pays "
        "less of it, so it trains for the time to a certain map",
        step_cost,
    ),
    RewardTerm(
        "coverage",
        0.0,
        "m^2 of the world the sensor looks at for the first time (the coverage memory): an exploration shaping "
        "for training, which the shipped EKFSLAM-v0 policy uses",
        coverage,
    ),
    RewardTerm(
        "pose_variance",
        0.0,
        "-tr Sigma_xy, m^2, the pose estimate's position variance, per control step: a cost on being lost, "
        "which pays for staying localised and closing loops (landmarks first seen from an uncertain pose are "
        "placed as uncertainly); the shipped EKFSLAM-Large-v0 policy uses it",
        pose_variance,
    ),
)

REWARD_NAMES: tuple[str, ...] = tuple(term.name for term in REWARD_TERMS)
_FUNCTIONS = tuple((term.name, term.value) for term in REWARD_TERMS)


def evaluate(context: StepContext) -> dict[str, float]:
    """Every term's unweighted value for one control step, by name, in ``REWARD_TERMS`` order."""
    terms = {}
    for name, value in _FUNCTIONS:  # a plain loop: a comprehension costs a frame of its own every step
        terms[name] = value(context)
    return terms


def nonzero_weights(weights: object) -> tuple[tuple[str, float], ...]:
    """(name, weight) of the terms a ``RewardConfig`` weighs, in ``REWARD_TERMS`` order."""
    return tuple((term.name, w) for term in REWARD_TERMS if (w := float(getattr(weights, term.name))))


def weigh(terms: Mapping[str, float], weights: tuple[tuple[str, float], ...]) -> float:
    """The reward: the weighted sum of ``terms`` over ``weights`` (from ``nonzero_weights``), in order."""
    reward = 0.0
    for name, weight in weights:
        reward += weight * terms[name]
    return reward
