"""The reward terms by name: the one list that makes ``RewardConfig``'s fields and picks the env's reward hooks.

The reward of a step is the sum of the terms whose weight is non-zero; ``info["reward_terms"]`` names each.
Every term is computed by the env's hook ``_reward_<name>(weight)`` (see ``EKFSLAMEnv._rewards``), so a new
term is one entry here and one method there. The information-theoretic terms are the optimality criteria of
experimental design applied to the SLAM covariance (D-, A- and E-optimality; see the README's *The maths,
briefly*, and the Freiburg *Robot Mapping* course by C. Stachniss on active SLAM).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RewardTerm:
    """One reward term: its name (the ``reward`` config field and the ``reward_terms`` key), its default
    weight and what the weight multiplies."""

    name: str
    default: float
    meaning: str


REWARD_TERMS: tuple[RewardTerm, ...] = (
    RewardTerm(
        "info_gain",
        1.0,
        "weight of log det Sigma_{t-1} - log det Sigma_t (the D-optimal information gain, the default)",
    ),
    RewardTerm("a_opt", 0.0, "weight of the drop of ln trace Sigma (A-optimality)"),
    RewardTerm("e_opt", 0.0, "weight of the drop of ln lambda_max(Sigma) (E-optimality)"),
    RewardTerm("collision", 1.0, "penalty per step in contact with a wall"),
    RewardTerm("control_effort", 0.0, "penalty times |action|^2"),
    RewardTerm(
        "step_cost", 0.0, "a constant cost per step (discourages idling once nothing is left to learn)"
    ),
    RewardTerm(
        "map_variance",
        0.0,
        "weight per m^2 drop of the summed position variances tr Sigma_jj of the landmarks already seen "
        "(info['belief_gain']): pays for making the mapped part more accurate (revisits, loop closures), which "
        "a consistent filter's landmark RMSE follows, and nothing for a discovery; 0 by default",
    ),
    RewardTerm(
        "pose_variance",
        0.0,
        "penalty per m^2 of the pose estimate's position variance tr Sigma_xy (x and y), per control step: "
        "a cost on being lost, which an absolute map inherits (landmarks first seen from an uncertain pose are "
        "placed as uncertainly), so it pays for staying localised and for closing loops; 0 by default",
    ),
    RewardTerm(
        "pose_error",
        0.0,
        "penalty per m^2 of the pose estimate's squared position error |(x, y) estimate - true|^2, per control "
        "step: pose_variance's counterpart in the truth, which also charges the over-confident pose (small "
        "variance, large error) that pose_variance cannot see; it reads the true pose, so it is for training "
        "only (the observation stays the belief, as in asymmetric actor-critic); 0 by default",
    ),
    RewardTerm(
        "map_accuracy",
        0.0,
        "weight per drop of ln R, R = sqrt(mean_j tr Sigma_jj) over the landmarks seen (the landmark RMSE a "
        "consistent filter expects): telescopes to w ln(R_first / R_final), so it charges discoveries placed "
        "less certainly than the map so far and pays loop closures; beside info_gain it weighs the map's "
        "accuracy against its certainty; 0 by default",
    ),
    RewardTerm(
        "map_error",
        0.0,
        "weight per m^2 drop of the seen landmarks' true mean squared position error (info['map_rmse']^2, the "
        "landmark RMSE the evaluation scores, squared): telescopes to w (MSE_first - MSE_final), so it charges a "
        "discovery placed worse than the map so far and pays a correction; map_accuracy's counterpart in the "
        "truth, for training only like pose_error (it reads the true landmarks); 0 by default",
    ),
    RewardTerm(
        "coverage",
        0.0,
        "bonus per m^2 of the world the sensor looks at for the first time (the coverage memory), an "
        "exploration shaping for training; 0 by default, so the default reward is the information gain and "
        "the collision penalty",
    ),
)

REWARD_NAMES: tuple[str, ...] = tuple(term.name for term in REWARD_TERMS)
