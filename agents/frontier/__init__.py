"""Nearest-frontier exploration (Yamauchi 1997, "A frontier-based approach for autonomous exploration"), the
standard baseline of the exploration literature, on the env's coverage memory.

Frontiers: cells of the coverage memory not yet looked at (and not known to be walls) that border a looked-at
cell, grouped into 8-connected regions; regions smaller than ``min_region`` cells are dropped (slivers along
walls). The goal is the frontier cell nearest by *path* distance, plus ``turn_cost`` m per radian the robot
must first turn to face it (with a field of view of half a circle, the frontier behind the robot is cheap
in metres but not in time). The path is a shortest path (Dijkstra, 8-connected) over the memory grid around
the walls the agent has mapped, searched only as far as the cheapest frontier and those within
``switch_margin`` of it need (``nearest_paths``: the same paths, bit for bit, at about half the cost of a
search of the whole grid on EKFSLAM-Large-v0); the waypoint controller (``ekfslam_gym.envs.waypoint``)
steers at the furthest point of it within ``lookahead`` m that no mapped wall hides. The agent plans again
when the goal has been looked at, every ``replan_every`` steps (keeping its goal unless another is
``switch_margin`` m nearer), or when it gives up on the goal.

Walls: the coverage memory ignores walls (it records where the sensor pointed), but the loop's central block
and the rooms' walls must be gone around, so the agent keeps an occupancy-style wall memory on the same grid
from the observation's wall scan, as the greedy planner does: each beam clears the cells it crosses; its end
point, and the surface joining it to a neighbouring end point closer than ``join`` m, mark walls. Unmapped
cells count as free (the optimistic assumption of planning in unknown space). A path starts in the robot's
cell, or, when that cell holds a wall (the robot is next to one), in the neighbouring cells the scan shows
on the robot's side of it. A goal that cannot be reached (the robot stalls, moving less than
``stall_distance`` m in ``stuck_steps`` steps, or the goal takes more than ``patience`` times its path's
driving time) is given up with the frontier cells within ``give_up_radius`` m of it, so a gap in the mapped
walls of a closed block is tried once, not forever.

Revisiting: when no frontier is left, or every landmark the filter carries has been seen (its state has one
slot per landmark, so nothing is left to discover), the agent improves the map it has (Thrun, Burgard & Fox,
*Probabilistic Robotics*, ch. 17: re-observing mapped landmarks to close loops). It drives to the seen
landmark whose estimate has been out of the sensor's range and field of view the longest until that landmark
is within ``revisit_range`` m in the field of view, then picks the next, skipping the ``revisit_memory`` most
recent (the stalest first did better than the most uncertain first: docs/research-log-v0.md keeps the record).

Active loop closing (Stachniss, Hahnel & Burgard 2004, "Exploration with active loop-closing for FastSLAM";
off by default): with ``relocalize_std`` set, when the pose estimate's position standard deviation
sqrt(tr Sigma_xy) exceeds it, the agent stops exploring and drives to the nearest (by path) seen landmark
that is much more certain than the pose (marginal position std below ``anchor_ratio`` times the pose's), one
after another, until the pose's std falls below ``relocalize_until`` times ``relocalize_std``. Exploring from
an uncertain pose places every new landmark as uncertainly, so this trades landmarks seen for an accurate
map.

Uses only the belief: the filter's mean and covariance, the coverage memory, the wall scan, the config and the
world's bounds; never the true map or pose.

The package by job: ``agent`` (``FrontierAgent``: the mode state machine, ``Mode``, and the velocity commands),
``geometry`` (cells, bearings, the robot frame), ``planners`` (the planner in the macro action interfaces, for
behaviour cloning and DAgger). The grid, the wall memory, Dijkstra and the wall veto are the planners' shared
pieces in ``ekfslam_gym.agents.navigation``.
"""

from ..navigation import frontier_cells, frontier_regions, grid_paths, path_sources
from .agent import FrontierAgent, Mode, coverage_and_bounds
from .planners import FrontierPrimitivesPlanner, FrontierWaypointPlanner

# The grid pieces above are ``ekfslam_gym.agents.navigation``'s, named here too for code written against the
# frontier module before the split (the team env's baselines); new code imports them from navigation.

__all__ = [
    "FrontierAgent",
    "FrontierPrimitivesPlanner",
    "FrontierWaypointPlanner",
    "Mode",
    "coverage_and_bounds",
    "frontier_cells",
    "frontier_regions",
    "grid_paths",
    "path_sources",
]
