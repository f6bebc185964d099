"""What the planners share: a grid over the world, the wall memory built from the wall scan, where a sensor has
looked, shortest paths around the remembered walls, the frontiers of the unexplored, and the wall veto of a
motion primitive. Nothing here reads an env: every function takes arrays and numbers, so a planner of another
env (a team of robots) reuses them as they are.

The grid convention, the same in every module: a grid is a 2-D array (ny, nx) whose row ``r`` and column ``c``
cover the square [xmin + c cell, xmin + (c + 1) cell) x [ymin + r cell, ymin + (r + 1) cell), in metres, so rows
run along y and columns along x (the env's coverage memory is laid out so). A wall grid is boolean (True: a
wall); a cost grid is float with ``inf`` where a cell is no source or unreachable. Poses are (x, y, heading) in
metres and radians; a wall scan is one range per beam (m), beam i at heading + ``angles[i]``, a range at or
beyond ``scan_max`` having hit nothing.

- ``walls``: the wall memory from scans (``update_walls``), and straight lines checked against it;
- ``view``: the cells wholly in a sensor's range and field of view (``mark_seen``, ``count_new``);
- ``paths``: Dijkstra (``grid_paths``, ``nearest_paths``), the chamfer ``distance_field``, where paths start
  (``path_sources``), the path back from a search (``trace_path``) and the point to steer at (``carrot``);
- ``frontiers``: frontier cells and regions of a coverage memory, and the distance field to the unexplored;
- ``veto``: the wall scan as points and segments in the robot frame, a primitive's arc, and its veto.

The grid kernels are compiled with numba (they run at every step).
"""

from .frontiers import frontier_cells, frontier_field, frontier_regions
from .paths import carrot, distance_field, grid_paths, nearest_paths, path_sources, trace_path
from .veto import WALL_JOIN, arc_poses, arc_vetoed, clearances, scan_geometry, to_world
from .view import cell_in_view, count_new, mark_seen
from .walls import behind_wall, line_is_free, paint, update_walls

__all__ = [
    "WALL_JOIN",
    "arc_poses",
    "arc_vetoed",
    "behind_wall",
    "carrot",
    "cell_in_view",
    "clearances",
    "count_new",
    "distance_field",
    "frontier_cells",
    "frontier_field",
    "frontier_regions",
    "grid_paths",
    "line_is_free",
    "mark_seen",
    "nearest_paths",
    "paint",
    "path_sources",
    "scan_geometry",
    "to_world",
    "trace_path",
    "update_walls",
]
