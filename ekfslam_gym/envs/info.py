"""The keys of the ``info`` dict that ``EKFSLAMEnv.reset`` and ``step`` return: one table, which the docs page
``docs/belief-and-truth.md`` is generated from and the tests hold to the env's real keys.

Each key says whether it comes from the filter's belief (what the agent may know), from the simulator's truth
(privileged: for evaluation, baselines and training signals, never for a deployed policy), from both (a
comparison of the two), or from the episode's bookkeeping.
"""

from __future__ import annotations

from typing import NamedTuple


class InfoKey(NamedTuple):
    name: str
    unit: str
    source: str  # belief | truth | both | episode
    meaning: str
    # Only in a step's info with macro actions (primitives, waypoint, velocity held > 1).
    macro_only: bool = False


# name | unit | source | meaning: one row a key, in the order the env writes them.
_TABLE = """
step                | control steps                   | episode | control steps since reset (``env.unwrapped.elapsed_steps``)
true_pose           | m, m, rad                       | truth   | the robot's true pose (x, y, theta)
pose                | m, m, rad                       | belief  | the filter's pose estimate (x, y, theta)
pose_cov            | m^2, rad^2                      | belief  | the pose estimate's marginal covariance (3, 3)
log_det             | nats                            | belief  | log det Sigma of the filter's full, fixed-size covariance; its drop over a step is the unweighted information gain
reward_terms        | per term                        | both    | every reward term by name, unweighted, summed over a macro step's control steps; the reward is the sum of each times its weight in ``reward``; all 0 at reset
truth_gain          | m^2                             | truth   | the drop over the step of the summed squared position errors of the landmarks seen both before and after it
belief_gain         | m^2                             | belief  | the drop over the step of the same landmarks' summed marginal position variances tr Sigma_jj: what a consistent filter expects ``truth_gain`` to be
landmarks_seen      | count                           | both    | landmarks (slots holding a true landmark) the filter has mapped
collision           | bool                            | truth   | the robot touched a wall during the step (during any of a macro step's control steps)
collisions          | control steps                   | truth   | control steps in contact with a wall since reset
pose_nees           | chi^2, 3 dof                    | both    | the pose estimate's normalised estimation error squared (NaN on a failed step)
map_rmse            | m                               | both    | RMS position error of the mapped landmarks against the truth (NaN before the first or on a failed step)
loop_closures       | count                           | belief  | re-observations of a landmark unseen for at least ``loop_gap`` control steps, since reset
path_length         | m                               | truth   | distance the robot has truly travelled since reset
odometry            | m, or m and rad, or m/s and rad/s | belief  | the last control step's odometry as the filter's motion model takes it (wheels: left, right, slip; odometry: rot1, trans, rot2; velocity: v, omega); zeros at reset
odometry_cov        | its units squared               | belief  | the covariance the odometry reports with it
readings            | slot ids; m and rad             | belief  | the (ids, z) readings the filter used in the last control step: z rows (range, bearing), ids the slots they were used for
filter_failed       | bool                            | belief  | the filter failed numerically on this step: the episode is terminated, and a macro step's reward and ``reward_terms`` are those of its control steps before the failure (the failed one adds 0)
false_associations  | count                           | truth   | readings matched to a slot holding another landmark, or clutter matched to any slot, since reset (0 with known association)
missed_associations | count                           | truth   | readings of true landmarks neither matched nor starting a landmark, since reset (0 with known association)
time_to_complete    | s                               | belief  | simulated time from reset until the map was first complete (every landmark's marginal sigma below ``done_std``), inf until then; the episode ends there only with ``terminate_on_complete`` (v0), the v1 ids run on to their horizon
inner_steps         | control steps                   | episode | control steps the macro step ran
inner_actions       | fractions of v_max, omega_max   | episode | the (forward, turn) command of each of them, (inner_steps, 2)
"""
_MACRO_ONLY = {"inner_steps", "inner_actions"}

INFO_KEYS: tuple[InfoKey, ...] = tuple(
    InfoKey(*(cell.strip() for cell in row.split("|")), macro_only=row.split("|")[0].strip() in _MACRO_ONLY)
    for row in _TABLE.strip().splitlines()
)


def info_keys(macro: bool) -> tuple[str, ...]:
    """The names of the keys a step of an env with (``macro``) or without macro actions returns; ``reset``
    returns those of a non-macro step."""
    return tuple(key.name for key in INFO_KEYS if macro or not key.macro_only)
