"""The greedy information-gain planner: the classic D-optimal active-SLAM baseline.

For each of a few motion primitives (a (v, omega) command held for ``horizon`` steps) the planner rolls a copy
of the env's EKF forward: at every step a prediction with the odometry the primitive would produce and that
odometry's noise (the simulator's alpha model, from the env's config), then a correction with the readings
*expected* from the current estimate: every seen landmark whose estimated position lies within range and
field of view of the predicted pose, read exactly (z = h(predicted pose, estimated landmark), no noise, so the
mean stays put and only the covariance moves). The expected gain is log det Sigma now - log det Sigma after.

That alone cannot value the unknown: an unseen landmark has no estimate to predict a reading of, so a pure
D-optimal planner circles what it already knows. Two terms in the same unit (nats) fix that:

- discovery: the planner keeps its own coverage grid (``cell`` m) of where its sensor has looked, marked from
  the pose estimate, the sensor's range and field of view (a cell counts only once all of it was in view),
  and hidden behind a wall memory built from the observation's wall scan (cells that beams end in are walls,
  cells they cross are cleared again). It is the same information as the observation's coverage window, at
  a finer resolution. Unseen landmarks are assumed uniform over the unlooked-at cells, so a primitive whose
  predicted field of view sweeps ``c`` new cells expects ``n_unseen * c / n_unlooked`` discoveries, each
  worth the information a first reading gives: ln(prior^2) - E[ln det(Gz Q Gz^T)], about 20 nats by default.
- frontier: beyond one horizon, ``frontier_weight`` nats per metre of progress along the shortest path
  around the remembered walls to the unexplored, measured from a point ``lookahead`` m ahead of the robot
  (so turning towards it pays before driving does). Each unlooked-at cell is a goal with an extra cost of
  -``frontier_scale`` ln(the fraction of unlooked-at cells within 4 m of it), so large unexplored regions
  beat nearer slivers along the walls. A straight-line version of this term pulled the robot into walls
  between it and the unexplored (the loop's central block, the next room), where it stayed.

Cells hidden behind remembered walls in ``give_up`` views are no longer sought (the inside of a closed
block cannot be looked at), and the primitive being executed gets ``commitment`` nats when replanning, so a
near-tie between turning left and right does not flip at every replan.

Walls: the planner does *not* use the privileged wall geometry. It vetoes a primitive when its path, in the
robot frame, comes closer than ``robot radius + clearance`` to the wall scan of the current observation (beam
end points, joined into segments where neighbouring beams hit the same surface) while closing in, or leaves
the world's bounds. Turning in place is never vetoed, so there is always a way out. The coverage grid, the wall
memory, the distance field and the veto are the planners' shared pieces (``ekfslam_gym.agents.navigation``).

Cost: ``len(primitives)`` rollouts of ``horizon`` predict/correct pairs every ``replan_every`` steps (and
sooner if the new scan vetoes the primitive being executed), plus one shortest-path sweep of the grid: about
5 ms a plan, 500 decisions/s in the default env, 200 in EKFSLAM-Large-v0 (120 landmarks).

Two-step lookahead (``depth=2``, the ``greedy2`` agent): a one-step planner cannot value a turn by what driving
after it would see. Each first primitive then also earns ``discount`` times the best score of a second
primitive continued from where the first ends: its rollout starts from the first's rolled-forward belief (the
same copy, predicted and corrected with the expected readings), its wall veto checks the combined path against
the same scan, and its discovery counts only cells the first did not already sweep. The frontier term
telescopes (the second measures progress from the first's end), and the frontier field is not recomputed.
The cost is ``len(primitives) + len(primitives)^2`` rollouts a plan instead of ``len(primitives)``.
"""

from .agent import GreedyInfoGainAgent, GreedyLookaheadAgent
from .rollout import (
    DEFAULT_PRIMITIVES,
    discovery_nats,
    expected_readings,
    primitive_controls,
    rollout,
    rollout_gain,
)

__all__ = [
    "DEFAULT_PRIMITIVES",
    "GreedyInfoGainAgent",
    "GreedyLookaheadAgent",
    "discovery_nats",
    "expected_readings",
    "primitive_controls",
    "rollout",
    "rollout_gain",
]
