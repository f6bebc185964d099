"""Procedural layout families beyond the first three: an arena with pillars, a figure eight of corridors, an
office (rooms off a corridor spine), a warehouse (aisles between rows of shelves) and a maze (corridors and dead
ends).

Each is a pure function of its ``numpy.random.Generator`` and a few keywords (documented in each docstring's
``Keywords:`` section, which the registry in ``layouts`` reads), checks its keywords before it draws anything,
and builds its walls from axis-aligned segments merged into as few as it can: the sensor's occlusion test costs
one check per wall. Landmarks are placed as everywhere else (``layout_base.place_landmarks``: exact count, clear
of walls, reachable from the start). Units: metres and radians; a world spans (0, 0, width, height).
"""

from __future__ import annotations

import math

import numpy as np

from .layout_base import (
    Layout,
    Wall,
    box_walls,
    check_int,
    check_passage,
    check_range,
    check_size,
    finish,
    start_pose,
    wall_runs,
)


def _check_thin_block(name: str, size: float, start_clearance: float) -> None:
    """ValueError unless a closed block of this ``size`` is too thin to hold the start pose inside it."""
    if not (math.isfinite(size) and 0.0 < size < 2.0 * start_clearance):
        raise ValueError(
            f"{name} must be in (0, 2 start_clearance) = (0, {2.0 * start_clearance}) m, got {size!r}: a thicker "
            "block could hold the start inside it"
        )


def pillars(
    rng: np.random.Generator,
    n_landmarks: int = 30,
    *,
    width: float = 22.0,
    height: float = 22.0,
    n_pillars: int = 14,
    pillar_size: float = 1.0,
    gap: float = 1.5,
    min_spacing: float = 1.0,
    landmark_clearance: float = 0.5,
    start_clearance: float = 1.0,
    robot_radius: float = 0.2,
    wall_radius: float = 0.05,
) -> Layout:
    """An open hall with square pillars standing at random: each pillar hides what is behind it.

    Pillars are at least ``gap`` m from each other and from the outer walls, so the free space stays connected
    and every landmark reachable; the start is uniform in the hall, outside every pillar.

    Keywords:
        width, height: m, the world's size.
        n_pillars: pillars, placed at random.
        pillar_size: m, a pillar's side, less than 2 start_clearance (no start inside a pillar).
        gap: m, the least free gap between two pillars and between a pillar and an outer wall.
    """
    check_size(width, height, 2.0 * start_clearance + 0.1)
    check_int("n_pillars", n_pillars, 0)
    _check_thin_block("pillar_size", pillar_size, start_clearance)
    check_passage("gap", gap, robot_radius, wall_radius)
    half = 0.5 * pillar_size
    lo = np.array([gap + half, gap + half])
    hi = np.array([width - gap - half, height - gap - half])
    if np.any(hi < lo):
        raise ValueError(f"a {width} x {height} m hall has no room for a pillar with gap {gap} m")
    centres = np.empty((int(n_pillars), 2))
    placed = 0
    pitch = pillar_size + gap  # squares whose centres differ this much along one axis are gap apart
    for _ in range(200 * int(n_pillars)):
        if placed == n_pillars:
            break
        candidate = lo + (hi - lo) * rng.random(2)
        if placed == 0 or np.abs(centres[:placed] - candidate).max(axis=1).min() >= pitch:
            centres[placed] = candidate
            placed += 1
    if placed < n_pillars:
        raise ValueError(
            f"could place only {placed} of {n_pillars} pillars {pillar_size} m wide with gap {gap} m in a "
            f"{width} x {height} m hall; use fewer or smaller pillars, a smaller gap or a larger hall"
        )
    walls: list[Wall] = box_walls(0.0, 0.0, width, height)
    for x, y in centres.tolist():
        walls += box_walls(x - half, y - half, x + half, y + half)
    walls_array = np.array(walls)
    bounds = np.array([0.0, 0.0, width, height])
    start = start_pose(rng, walls_array, bounds[:2], bounds[2:], start_clearance)
    return finish(
        "pillars", rng, n_landmarks, walls_array, bounds, start, min_spacing=min_spacing,
        landmark_clearance=landmark_clearance, robot_radius=robot_radius, wall_radius=wall_radius,
    )  # fmt: skip


def figure_eight(
    rng: np.random.Generator,
    n_landmarks: int = 30,
    *,
    width: float = 30.0,
    height: float = 16.0,
    corridor: float = 3.5,
    jitter: float = 0.15,
    min_spacing: float = 1.0,
    landmark_clearance: float = 0.5,
    start_clearance: float = 1.0,
    robot_radius: float = 0.2,
    wall_radius: float = 0.05,
) -> Layout:
    """Two corridor rings that share their middle corridor, round two closed blocks: two loops to close, and
    a crossing where the robot chooses which.

    Each of the five corridors (left, right, middle, bottom, top) is ``corridor`` m wide, scaled by up to
    1 +- ``jitter``; the middle corridor's position shifts by up to ``jitter`` / 4 of the width. The start is on
    the centre line of a random corridor, heading along it.

    Keywords:
        width, height: m, the world's size.
        corridor: m, the corridors' width.
        jitter: each corridor's width is scaled by up to 1 +- this, in [0, 0.5).
    """
    check_size(width, height, 2.0)
    check_range("jitter", jitter, 0.0, 0.5)
    if corridor * (1.0 - jitter) < 2.0 * start_clearance:
        raise ValueError(f"corridor ({corridor} m) is too narrow for start_clearance {start_clearance} m")
    left, right, middle, bottom, top = corridor * (1.0 + rng.uniform(-jitter, jitter, 5))
    centre = width * (0.5 + rng.uniform(-0.25, 0.25) * jitter)
    block_a = (left, bottom, centre - 0.5 * middle, height - top)
    block_b = (centre + 0.5 * middle, bottom, width - right, height - top)
    if min(block_a[2] - block_a[0], block_b[2] - block_b[0], height - top - bottom) < 1.0:
        raise ValueError(f"corridor ({corridor} m) leaves no blocks in a {width} x {height} m world")
    walls = np.array(box_walls(0.0, 0.0, width, height) + box_walls(*block_a) + box_walls(*block_b))
    bounds = np.array([0.0, 0.0, width, height])
    # the corridors' centre lines: (x0, y0, x1, y1), driven from the first end to the second
    lines = (
        (0.5 * left, bottom, 0.5 * left, height - top),
        (width - 0.5 * right, bottom, width - 0.5 * right, height - top),
        (centre, bottom, centre, height - top),
        (left, 0.5 * bottom, width - right, 0.5 * bottom),
        (left, height - 0.5 * top, width - right, height - 0.5 * top),
    )
    x0, y0, x1, y1 = lines[int(rng.integers(len(lines)))]
    u = rng.uniform(0.1, 0.9)
    heading = math.atan2(y1 - y0, x1 - x0) + (math.pi if rng.random() < 0.5 else 0.0)
    start = np.array([x0 + u * (x1 - x0), y0 + u * (y1 - y0), math.remainder(heading, 2.0 * math.pi)])
    return finish(
        "figure_eight", rng, n_landmarks, walls, bounds, start, min_spacing=min_spacing,
        landmark_clearance=landmark_clearance, robot_radius=robot_radius, wall_radius=wall_radius,
    )  # fmt: skip


def _split(rng: np.random.Generator, length: float, parts: int, jitter: float) -> np.ndarray:
    """``parts + 1`` cut points from 0 to ``length``, the inner ones moved by up to ``jitter`` of a part."""
    cuts = np.linspace(0.0, length, parts + 1)
    cuts[1:-1] += rng.uniform(-jitter, jitter, parts - 1) * (length / parts)
    return cuts


def _line_with_doors(
    fixed: float, a: float, b: float, doors: list[tuple[float, float]], vertical: bool
) -> list[Wall]:
    """The wall along one axis from ``a`` to ``b`` at ``fixed`` on the other, open over each (lo, hi) of
    ``doors`` (sorted, inside [a, b])."""
    walls: list[Wall] = []
    position = a
    for lo, hi in [*doors, (b, b)]:
        if lo - position > 1e-9:
            walls.append((fixed, position, fixed, lo) if vertical else (position, fixed, lo, fixed))
        position = hi
    return walls


def office(
    rng: np.random.Generator,
    n_landmarks: int = 30,
    *,
    width: float = 28.0,
    height: float = 18.0,
    rooms_per_side: int = 4,
    corridor: float = 2.5,
    door_width: float = 1.2,
    jitter: float = 0.15,
    min_spacing: float = 1.0,
    landmark_clearance: float = 0.5,
    start_clearance: float = 1.0,
    robot_radius: float = 0.2,
    wall_radius: float = 0.05,
) -> Layout:
    """Rooms off a corridor spine: a corridor across the whole width, a row of rooms on each side, each room
    with one door onto the corridor. Every room is a dead end, so the robot goes in and comes back out.

    Partitions between rooms shift by up to ``jitter`` of a room's width (each side drawn apart), the spine by
    up to ``jitter`` / 4 of the height; the start is on the corridor's centre line, heading along it.

    Keywords:
        width, height: m, the world's size.
        rooms_per_side: rooms along each side of the corridor.
        corridor: m, the spine corridor's width.
        door_width: m, every door's width.
        jitter: partitions shift by up to this fraction of a room's width, in [0, 0.5).
    """
    check_size(width, height, 2.0)
    check_int("rooms_per_side", rooms_per_side, 1)
    check_range("jitter", jitter, 0.0, 0.5)
    check_passage("door_width", door_width, robot_radius, wall_radius)
    if corridor < 2.0 * start_clearance:
        raise ValueError(f"corridor ({corridor} m) is too narrow for start_clearance {start_clearance} m")
    margin = wall_radius + 0.3
    room_width = width / rooms_per_side * (1.0 - 2.0 * jitter)
    spine = 0.5 * height * (1.0 + rng.uniform(-0.25, 0.25) * jitter)
    low, high = spine - 0.5 * corridor, spine + 0.5 * corridor
    if room_width < door_width + 2.0 * margin or min(low, height - high) < 2.0 * start_clearance:
        raise ValueError(
            f"a {width} x {height} m office has no room for {rooms_per_side} rooms a side off a {corridor} m "
            f"corridor with {door_width} m doors; use fewer rooms or a larger office"
        )
    walls: list[Wall] = box_walls(0.0, 0.0, width, height)
    for wall_y, far_y in ((low, 0.0), (high, height)):
        cuts = _split(rng, width, rooms_per_side, jitter)
        doors = []
        for a, b in zip(cuts[:-1], cuts[1:]):
            centre = rng.uniform(a + margin + 0.5 * door_width, b - margin - 0.5 * door_width)
            doors.append((centre - 0.5 * door_width, centre + 0.5 * door_width))
        walls += _line_with_doors(wall_y, 0.0, width, doors, vertical=False)
        walls += [(x, min(wall_y, far_y), x, max(wall_y, far_y)) for x in cuts[1:-1].tolist()]
    walls_array = np.array(walls)
    bounds = np.array([0.0, 0.0, width, height])
    heading = 0.0 if rng.random() < 0.5 else math.pi
    start = np.array([width * rng.uniform(0.1, 0.9), spine, heading])
    return finish(
        "office", rng, n_landmarks, walls_array, bounds, start, min_spacing=min_spacing,
        landmark_clearance=landmark_clearance, robot_radius=robot_radius, wall_radius=wall_radius,
    )  # fmt: skip


def warehouse(
    rng: np.random.Generator,
    n_landmarks: int = 30,
    *,
    width: float = 24.0,
    height: float = 20.0,
    n_rows: int = 5,
    shelf_depth: float = 1.0,
    end_aisle: float = 3.0,
    n_cross: int = 1,
    cross_aisle: float = 2.0,
    min_spacing: float = 1.0,
    landmark_clearance: float = 0.5,
    start_clearance: float = 1.0,
    robot_radius: float = 0.2,
    wall_radius: float = 0.05,
) -> Layout:
    """Aisles between long rows of shelves: a row hides every aisle beyond it, so the robot sees one aisle at
    a time, and long straight aisles look alike.

    ``n_rows`` rows of shelves ``shelf_depth`` m deep run along x between two end aisles ``end_aisle`` m wide,
    evenly spaced in y; ``n_cross`` cross aisles ``cross_aisle`` m wide, at random places common to every
    row, cut through them. The start is in an end aisle.

    Keywords:
        width, height: m, the world's size.
        n_rows: rows of shelves.
        shelf_depth: m, a row's depth, less than 2 start_clearance (no start inside a shelf).
        end_aisle: m, the width of the open aisle at each end of the rows.
        n_cross: cross aisles through every row.
        cross_aisle: m, a cross aisle's width.
    """
    check_size(width, height, 2.0)
    check_int("n_rows", n_rows, 1)
    check_int("n_cross", n_cross, 0)
    _check_thin_block("shelf_depth", shelf_depth, start_clearance)
    check_passage("cross_aisle", cross_aisle, robot_radius, wall_radius)
    if end_aisle < 2.0 * start_clearance:
        raise ValueError(f"end_aisle ({end_aisle} m) is too narrow for start_clearance {start_clearance} m")
    aisle = (height - n_rows * shelf_depth) / (n_rows + 1)
    check_passage(f"the aisle between rows ({n_rows} rows in {height} m)", aisle, robot_radius, wall_radius)
    length = width - 2.0 * end_aisle
    pieces = n_cross + 1
    shelf_length = (length - n_cross * cross_aisle) / pieces
    if shelf_length < 1.0:
        raise ValueError(
            f"{n_cross} cross aisles of {cross_aisle} m leave shelves under 1 m long in a {width} m warehouse"
        )
    # the shelves' lengths vary by up to a third, the cross aisles keep their width
    lengths = shelf_length * (1.0 + rng.uniform(-1.0 / 3.0, 1.0 / 3.0, pieces))
    lengths *= (length - n_cross * cross_aisle) / lengths.sum()
    walls: list[Wall] = box_walls(0.0, 0.0, width, height)
    for row in range(n_rows):
        y0 = aisle * (row + 1) + shelf_depth * row
        x = end_aisle
        for piece in lengths.tolist():
            walls += box_walls(x, y0, x + piece, y0 + shelf_depth)
            x += piece + cross_aisle
    walls_array = np.array(walls)
    bounds = np.array([0.0, 0.0, width, height])
    x_lo = 0.0 if rng.random() < 0.5 else width - end_aisle
    start = start_pose(
        rng, walls_array, np.array([x_lo, 0.0]), np.array([x_lo + end_aisle, height]), start_clearance
    )
    return finish(
        "warehouse", rng, n_landmarks, walls_array, bounds, start, min_spacing=min_spacing,
        landmark_clearance=landmark_clearance, robot_radius=robot_radius, wall_radius=wall_radius,
    )  # fmt: skip


def _spanning_tree(rng: np.random.Generator, rows: int, cols: int, braid: float) -> np.ndarray:
    """The closed edges (2, rows + 1, cols + 1) of a maze on a rows x cols grid of cells (``wall_runs``'
    layout): a random spanning tree of the cells (Kruskal's algorithm over one random order of the inner
    walls), then a fraction ``braid`` of the walls it kept opened at random, each opening a loop."""
    closed = np.zeros((2, rows + 1, cols + 1), dtype=bool)
    closed[0, :, :cols] = True
    closed[1, :rows, :] = True
    # inner walls: horizontal ones between cells (k - 1, c) and (k, c), vertical ones between (r, k - 1) and (r, k)
    inner = [(0, k, c) for k in range(1, rows) for c in range(cols)]
    inner += [(1, r, k) for r in range(rows) for k in range(1, cols)]
    parent = list(range(rows * cols))

    def root(cell: int) -> int:
        while parent[cell] != cell:
            parent[cell] = parent[parent[cell]]
            cell = parent[cell]
        return cell

    kept = []
    for index in rng.permutation(len(inner)).tolist():
        axis, k, c = inner[index]
        a, b = ((k - 1) * cols + c, k * cols + c) if axis == 0 else (k * cols + c - 1, k * cols + c)
        ra, rb = root(a), root(b)
        if ra != rb:
            parent[ra] = rb
            closed[axis, k, c] = False
        else:
            kept.append((axis, k, c))
    if braid > 0.0 and kept:
        for index in np.flatnonzero(rng.random(len(kept)) < braid).tolist():
            closed[kept[index]] = False
    return closed


def maze(
    rng: np.random.Generator,
    n_landmarks: int = 30,
    *,
    width: float = 20.0,
    height: float = 20.0,
    cell: float = 2.5,
    braid: float = 0.0,
    min_spacing: float = 1.0,
    landmark_clearance: float = 0.5,
    start_clearance: float = 1.0,
    robot_radius: float = 0.2,
    wall_radius: float = 0.05,
) -> Layout:
    """A maze of corridors one cell wide, branching and ending in dead ends: a random spanning tree of a grid of
    cells, so (with ``braid`` 0) there is exactly one way between two places and no loop to close.

    The grid has floor(width / cell) x floor(height / cell) cells, stretched to fill the world; the start is
    at the centre of a random cell with a uniform heading.

    Keywords:
        width, height: m, the world's size.
        cell: m, a corridor's width (the grid's cell), at least 2 start_clearance.
        braid: the fraction of the maze's inner walls opened after it is drawn, each making a loop, in [0, 1).
    """
    check_size(width, height, 2.0)
    check_range("braid", braid, 0.0, 1.0)
    if not (math.isfinite(cell) and cell >= 2.0 * start_clearance):
        raise ValueError(f"cell must be >= 2 start_clearance = {2.0 * start_clearance} m, got {cell!r}")
    cols, rows = int(width // cell), int(height // cell)
    if min(cols, rows) < 2:
        raise ValueError(f"a {width} x {height} m maze of {cell} m cells needs at least 2 x 2 cells")
    step_x, step_y = width / cols, height / rows
    closed = _spanning_tree(rng, rows, cols, braid)
    walls = np.array(wall_runs(closed, 0.0, 0.0, step_x, step_y))
    bounds = np.array([0.0, 0.0, width, height])
    r, c = int(rng.integers(rows)), int(rng.integers(cols))
    start = np.array([(c + 0.5) * step_x, (r + 0.5) * step_y, rng.uniform(-math.pi, math.pi)])
    return finish(
        "maze", rng, n_landmarks, walls, bounds, start, min_spacing=min_spacing,
        landmark_clearance=landmark_clearance, robot_radius=robot_radius, wall_radius=wall_radius,
    )  # fmt: skip
