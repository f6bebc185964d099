"""What every layout generator shares: the ``Layout`` record, landmark placement in the reachable free space,
start poses, and the wall helpers.

Landmarks are placed by rejection sampling: at least ``landmark_clearance`` from every wall centre line, at least
``min_spacing`` apart, and in the part of the free space the robot can reach from its start (a flood fill of an
occupancy grid), so no landmark sits inside a wall or a closed block. The count is exact or the generator raises
``ValueError``.

Units: metres and radians. A world spans ``bounds = (xmin, ymin, xmax, ymax)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import compiled

Wall = tuple[float, float, float, float]

COMMON_KEYWORDS: dict[str, str] = {
    "min_spacing": "m, the least distance between two landmarks",
    "landmark_clearance": "m, the least distance from a landmark to a wall's centre line",
    "start_clearance": "m, the least distance from the start to a wall's centre line",
    "robot_radius": "m, the robot the reachability check is for (the env passes `robot.radius`)",
    "wall_radius": "m, half a wall's thickness",
}
"""The keywords most generators take, documented once (each generator's docstring documents its own)."""


@dataclass(frozen=True, eq=False)
class Layout:
    """A static world: read-only arrays, validated at construction.

    name: the generator's name. walls: (k, 4) float64 segments [x1, y1, x2, y2] (m), centre lines of capsules of
    radius ``wall_radius`` (m). landmarks: (n, 2) float64 (m). start: (3,) float64 pose (x m, y m, theta rad).
    bounds: (4,) float64 (xmin, ymin, xmax, ymax) (m).
    """

    name: str
    walls: np.ndarray
    landmarks: np.ndarray
    start: np.ndarray
    bounds: np.ndarray
    wall_radius: float

    def __post_init__(self) -> None:
        for field, shape in (("walls", (-1, 4)), ("landmarks", (-1, 2)), ("start", (3,)), ("bounds", (4,))):
            array = np.array(getattr(self, field), dtype=np.float64)
            if array.ndim != len(shape) or any(s not in (-1, a) for s, a in zip(shape, array.shape)):
                raise ValueError(f"Layout.{field} must have shape {shape}, got {array.shape}")
            if not np.all(np.isfinite(array)):
                raise ValueError(f"Layout.{field} must be finite")
            array.flags.writeable = False
            object.__setattr__(self, field, array)
        if not (math.isfinite(self.wall_radius) and self.wall_radius > 0.0):
            raise ValueError(f"Layout.wall_radius must be finite and > 0, got {self.wall_radius!r}")

    def __reduce__(self) -> tuple:
        # rebuild through __init__ so an unpickled layout is validated and read-only again
        return (Layout, (self.name, self.walls, self.landmarks, self.start, self.bounds, self.wall_radius))

    @property
    def n_landmarks(self) -> int:
        """Number of landmarks n."""
        return int(self.landmarks.shape[0])


def box_walls(x0: float, y0: float, x1: float, y1: float) -> list[Wall]:
    """The four walls of the rectangle [x0, x1] x [y0, y1]."""
    return [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]


# Free-space grids of recent wall sets, and the reachable components found in them: an arena's walls are the
# same at every reset. Both are pure functions of their key, so reusing them changes nothing; at most this
# many wall sets are kept.
_GRID_CACHE_SIZE = 8
_grid_cache: dict[tuple, tuple[np.ndarray, list[np.ndarray]]] = {}


def _free_grid(
    walls: np.ndarray, bounds: np.ndarray, clearance: float, cell: float
) -> tuple[np.ndarray, list]:
    """(free mask (ny, nx), the connected components found so far in it), from the cache when it holds them.

    A cell is free when its centre is at least ``clearance + cell / 2`` from every wall centre line."""
    key = (walls.tobytes(), walls.shape, bounds.tobytes(), float(clearance), float(cell))
    entry = _grid_cache.get(key)
    if entry is None:
        nx = int(math.ceil((bounds[2] - bounds[0]) / cell))
        ny = int(math.ceil((bounds[3] - bounds[1]) / cell))
        free = compiled.free_cells(
            np.ascontiguousarray(walls, dtype=np.float64).reshape(-1, 4), float(bounds[0]), float(bounds[1]),
            float(cell), ny, nx, float(clearance + 0.5 * cell),
        )  # fmt: skip
        free.flags.writeable = False
        if len(_grid_cache) >= _GRID_CACHE_SIZE:
            del _grid_cache[next(iter(_grid_cache))]
        entry = _grid_cache[key] = (free, [])
    return entry


def _reachable_grid(
    walls: np.ndarray, bounds: np.ndarray, start_xy: np.ndarray, clearance: float, cell: float
) -> tuple[np.ndarray, np.ndarray]:
    """Cells whose centres the robot's centre can reach from ``start_xy``: (mask (ny, nx) bool, read-only,
    origin (2,)).

    A cell is free when its centre is at least ``clearance + cell / 2`` from every wall, so that two free
    neighbours are joined by a straight path of clearance >= ``clearance``: grid-connected implies reachable.
    """
    free, components = _free_grid(walls, bounds, clearance, cell)
    ny, nx = free.shape
    i = int((start_xy[1] - bounds[1]) // cell)
    j = int((start_xy[0] - bounds[0]) // cell)
    if not (0 <= i < ny and 0 <= j < nx) or not free[i, j]:
        raise ValueError("the start pose is not in free space (too close to a wall)")
    for component in components:
        if component[i, j]:
            return component, bounds[:2].copy()
    component = compiled.connected_component(free, i, j)
    component.flags.writeable = False
    components.append(component)
    return component, bounds[:2].copy()


def place_landmarks(
    rng: np.random.Generator,
    n_landmarks: int,
    walls: np.ndarray,
    bounds: np.ndarray,
    start: np.ndarray,
    *,
    min_spacing: float,
    landmark_clearance: float,
    robot_radius: float,
    wall_radius: float,
    max_candidates: int | None = None,
) -> np.ndarray:
    """Exactly ``n_landmarks`` points (n, 2), pairwise >= ``min_spacing`` apart, each >= ``landmark_clearance``
    from every wall centre line and where the robot (radius ``robot_radius``) can drive from ``start``.

    Raises ValueError if that many cannot be found among ``max_candidates`` uniform draws (default
    ``2000 + 200 n``), which means the world is too small or too crowded for the request.
    """
    if isinstance(n_landmarks, bool) or not isinstance(n_landmarks, (int, np.integer)) or n_landmarks < 0:
        raise ValueError(f"n_landmarks must be an int >= 0, got {n_landmarks!r}")
    robot_clearance = robot_radius + wall_radius
    if landmark_clearance <= robot_clearance:
        raise ValueError(
            f"landmark_clearance ({landmark_clearance} m) must exceed robot_radius + wall_radius "
            f"({robot_clearance} m), or landmarks could sit where the robot cannot go"
        )
    if not (math.isfinite(min_spacing) and min_spacing >= 0.0):
        raise ValueError(f"min_spacing must be finite and >= 0, got {min_spacing!r}")
    if n_landmarks == 0:
        return np.empty((0, 2))
    # a landmark's cell centre is within cell/sqrt(2) of it; choose the cell so that centre is a free cell
    cell = min(0.25, 0.95 * (landmark_clearance - robot_clearance) / (math.sqrt(0.5) + 0.5))
    reachable, origin = _reachable_grid(walls, bounds, start[:2], robot_clearance, cell)
    if max_candidates is None:
        max_candidates = 2000 + 200 * int(n_landmarks)

    lo = bounds[:2] + landmark_clearance
    hi = bounds[2:] - landmark_clearance
    accepted = np.empty((int(n_landmarks), 2))
    count = 0
    drawn = 0
    spacing2 = min_spacing * min_spacing
    batch = max(64, 4 * int(n_landmarks))
    while count < n_landmarks and drawn < max_candidates:
        size = min(batch, max_candidates - drawn)
        candidates = lo + (hi - lo) * rng.random((size, 2))
        drawn += size
        ok = compiled.min_wall_distance(candidates, walls) >= landmark_clearance
        cells = ((candidates - origin) // cell).astype(np.int64)
        ok &= reachable[
            cells[:, 1].clip(0, reachable.shape[0] - 1), cells[:, 0].clip(0, reachable.shape[1] - 1)
        ]
        count = compiled.accept_spaced(candidates[ok], accepted, count, spacing2)
    if count < n_landmarks:
        raise ValueError(
            f"could place only {count} of {n_landmarks} landmarks with min_spacing={min_spacing} m and "
            f"landmark_clearance={landmark_clearance} m after {drawn} candidates; use a larger world, fewer "
            "landmarks or a smaller spacing"
        )
    return accepted


def start_pose(
    rng: np.random.Generator,
    walls: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    clearance: float,
    heading: float | None = None,
) -> np.ndarray:
    """A pose uniform in the box [lo, hi] at least ``clearance`` from every wall; uniform heading unless given."""
    for _ in range(1000):
        xy = lo + (hi - lo) * rng.random(2)
        if compiled.min_wall_distance(xy[None, :], walls)[0] >= clearance:
            theta = rng.uniform(-math.pi, math.pi) if heading is None else heading
            return np.array([xy[0], xy[1], theta])
    raise ValueError(f"found no start pose with clearance {clearance} m")


def check_size(width: float, height: float, minimum: float) -> None:
    """ValueError unless the world's width and height are finite and at least ``minimum`` m."""
    if not (math.isfinite(width) and math.isfinite(height) and width >= minimum and height >= minimum):
        raise ValueError(f"width and height must be finite and >= {minimum} m, got {width!r} x {height!r}")


def check_int(name: str, value: object, minimum: int) -> None:
    """ValueError unless ``value`` is an int (not a bool) >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an int >= {minimum}, got {value!r}")


def check_range(name: str, value: float, low: float, high: float) -> None:
    """ValueError unless ``low <= value < high``."""
    if not (isinstance(value, (int, float)) and low <= value < high):
        raise ValueError(f"{name} must be in [{low}, {high}), got {value!r}")


def check_passage(name: str, width: float, robot_radius: float, wall_radius: float) -> None:
    """ValueError unless a gap of ``width`` m between two wall centre lines lets the robot through (0.1 m to
    spare)."""
    needed = 2.0 * (robot_radius + wall_radius) + 0.1
    if not (math.isfinite(width) and width > needed):
        raise ValueError(
            f"{name} ({width!r} m) is too narrow for the robot (radius {robot_radius} m): > {needed} m"
        )


def wall_runs(closed: np.ndarray, x0: float, y0: float, step_x: float, step_y: float) -> list[Wall]:
    """The walls of a grid's closed edges, each maximal straight run of closed edges merged into one segment
    (the sensor's occlusion test costs one check per wall, so few long walls beat many short ones).

    closed: (2, rows + 1, cols + 1) bool. ``closed[0, k, c]``: the horizontal edge on the grid line
    y = y0 + k step_y from x = x0 + c step_x to x0 + (c + 1) step_x (the last column unused); ``closed[1, k, c]``:
    the vertical edge on x = x0 + c step_x from y0 + k step_y to y0 + (k + 1) step_y (the last row unused).
    """
    walls: list[Wall] = []
    for axis in (0, 1):
        edges = closed[axis] if axis == 0 else closed[1].T
        padded = np.zeros((edges.shape[0], edges.shape[1] + 2), dtype=np.int8)
        padded[:, 1:-1] = edges
        change = np.diff(padded, axis=1)
        rows_s, starts = np.nonzero(change == 1)
        _, ends = np.nonzero(change == -1)
        for line, a, b in zip(rows_s.tolist(), starts.tolist(), ends.tolist()):
            if axis == 0:
                y = y0 + line * step_y
                walls.append((x0 + a * step_x, y, x0 + b * step_x, y))
            else:
                x = x0 + line * step_x
                walls.append((x, y0 + a * step_y, x, y0 + b * step_y))
    return walls


def finish(
    name: str,
    rng: np.random.Generator,
    n_landmarks: int,
    walls: list[Wall] | np.ndarray,
    bounds: np.ndarray,
    start: np.ndarray,
    *,
    min_spacing: float,
    landmark_clearance: float,
    robot_radius: float,
    wall_radius: float,
) -> Layout:
    """The layout of ``walls`` and ``start`` with ``n_landmarks`` placed where the robot can reach them."""
    walls_array = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    landmarks = place_landmarks(
        rng, n_landmarks, walls_array, bounds, start, min_spacing=min_spacing,
        landmark_clearance=landmark_clearance, robot_radius=robot_radius, wall_radius=wall_radius,
    )  # fmt: skip
    return Layout(name, walls_array, landmarks, start, bounds, wall_radius)
