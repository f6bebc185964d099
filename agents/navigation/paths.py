"""Shortest paths over a grid around the remembered walls: Dijkstra from one or many sources (``grid_paths``), the
same search stopped once the cheapest target is settled (``nearest_paths``), the chamfer distance field, where a
robot's paths start (``path_sources``), the path back from a search (``trace_path``) and the point of a path to
steer at (``carrot``). Grid convention: ``ekfslam_gym.agents.navigation``."""

from __future__ import annotations

import heapq
import math

import numpy as np
from numba import njit

from .walls import line_is_free


@njit(cache=True)
def grid_paths(blocked, start_cost, cell):
    """Shortest path lengths (m) over the cells not ``blocked`` (bool grid), 8-connected with no corner cut past
    a blocked cell (Dijkstra), from every cell with a finite ``start_cost`` (float grid: its cost at the start;
    the sources may be blocked themselves); ``cell`` m a side. Returns (distances (ny, nx), inf where
    unreachable; parents (ny * nx,) flat indices row * nx + col, -1 at the sources and where unreachable)."""
    target_cost = np.full(blocked.shape, np.inf)
    return nearest_paths(blocked, start_cost, cell, target_cost, 0.0)


@njit(cache=True)
def nearest_paths(blocked, start_cost, cell, target_cost, margin):
    """``grid_paths`` that stops once no cell left can be a target costing less than the cheapest found plus
    ``margin`` (m): a target's cost is its distance plus its ``target_cost`` (float grid, >= 0; inf where a cell
    is no target).

    The distances and parents it returns are ``grid_paths``' exactly, bit for bit, for every cell within the
    search (Dijkstra settles cells in order of distance, and the search is the same until it stops); the cells
    beyond it are inf and -1. So the cheapest target, and every target within ``margin`` of it, has its exact
    distance and path, while the nearest frontier costs a search of its distance's radius, not of the grid.
    With no target reached it is the full search."""
    ny, nx = blocked.shape
    n = ny * nx
    dist = start_cost.copy().reshape(n)
    extra = target_cost.reshape(n)
    parent = np.full(n, -1, dtype=np.int64)
    diagonal = cell * math.sqrt(2.0)
    heap = [(0.0, np.int64(0))]
    heap.pop()
    for u in range(n):
        if np.isfinite(dist[u]):
            heap.append((dist[u], np.int64(u)))
    heapq.heapify(heap)
    limit = np.inf  # the cheapest target's cost plus the margin (and a rounding's slack) so far
    while len(heap) > 0:
        d, u = heapq.heappop(heap)
        if d > dist[u]:
            continue
        if d > limit:  # every cell left is further than the limit: no cheaper target remains
            for v in range(n):
                if dist[v] > limit:
                    dist[v] = np.inf
                    parent[v] = -1
            break
        if d + extra[u] + margin < limit:
            limit = (d + extra[u] + margin) * (1.0 + 1e-12) + 1e-12
        row = u // nx
        col = u - row * nx
        for dr in range(-1, 2):
            r = row + dr
            if r < 0 or r >= ny:
                continue
            for dc in range(-1, 2):
                c = col + dc
                if (dr == 0 and dc == 0) or c < 0 or c >= nx or blocked[r, c]:
                    continue
                if dr != 0 and dc != 0:
                    if blocked[row + dr, col] or blocked[row, col + dc]:
                        continue
                    step = diagonal
                else:
                    step = cell
                v = r * nx + c
                if d + step < dist[v]:
                    dist[v] = d + step
                    parent[v] = u
                    heapq.heappush(heap, (d + step, v))
    return dist.reshape(ny, nx), parent


@njit(cache=True)
def distance_field(start_cost, wall, cell, max_sweeps):
    """Multi-source shortest path lengths (m) through the non-wall cells: d(p) = min over sources u of
    start_cost(u) + path length(u, p), 8-connected (no corner cutting past a wall), by alternating forward and
    backward chamfer sweeps (at most ``max_sweeps`` pairs) until nothing changes. ``start_cost`` is inf where a
    cell is not a source. Cheaper than Dijkstra when every cell's distance is wanted and the walls are few."""
    ny, nx = wall.shape
    d = start_cost.copy()
    diagonal = cell * math.sqrt(2.0)
    for _ in range(max_sweeps):
        changed = False
        for direction in (1, -1):
            rows = range(ny) if direction == 1 else range(ny - 1, -1, -1)
            for row in rows:
                cols = range(nx) if direction == 1 else range(nx - 1, -1, -1)
                for col in cols:
                    if wall[row, col]:
                        continue
                    best = d[row, col]
                    for dr, dc in ((-direction, -1), (-direction, 0), (-direction, 1), (0, -direction)):
                        r, c = row + dr, col + dc
                        if r < 0 or r >= ny or c < 0 or c >= nx or wall[r, c]:
                            continue
                        if dr != 0 and dc != 0:
                            if wall[row + dr, col] or wall[row, col + dc]:
                                continue
                            step = diagonal
                        else:
                            step = cell
                        if d[r, c] + step < best:
                            best = d[r, c] + step
                    if best < d[row, col]:
                        d[row, col] = best
                        changed = True
        if not changed:
            break
    return d


def path_sources(
    wall: np.ndarray, bounds: np.ndarray, cell: float, pose: np.ndarray, scan: np.ndarray, angles: np.ndarray
) -> np.ndarray:
    """Where paths start (the ``start_cost`` of ``grid_paths``) for a robot at ``pose`` in a grid whose corner
    is (``bounds[0]``, ``bounds[1]``): the robot's cell at cost 0; or, when the wall grid holds a wall in that
    cell (the robot is close to one), the free neighbouring cells on the robot's side of the wall, those whose
    centres both beams of ``scan`` (m, at ``angles``) around their direction show in the open, each at its
    straight-line distance. From the wall's cell itself a path could lead through the wall to its far side."""
    ny, nx = wall.shape
    col = min(max(int(math.floor((pose[0] - bounds[0]) / cell)), 0), nx - 1)
    row = min(max(int(math.floor((pose[1] - bounds[1]) / cell)), 0), ny - 1)
    cost = np.full(wall.shape, np.inf)
    if not wall[row, col]:
        cost[row, col] = 0.0
        return cost
    n = len(angles)
    width = 2.0 * math.pi / n
    for r in range(max(row - 1, 0), min(row + 2, ny)):
        for c in range(max(col - 1, 0), min(col + 2, nx)):
            if wall[r, c]:
                continue
            cx, cy = bounds[0] + (c + 0.5) * cell, bounds[1] + (r + 0.5) * cell
            distance = math.hypot(cx - pose[0], cy - pose[1])
            beam = ((math.atan2(cy - pose[1], cx - pose[0]) - pose[2]) % (2.0 * math.pi)) / width
            below = int(math.floor(beam)) % n
            if min(scan[below], scan[(below + 1) % n]) >= distance:
                cost[r, c] = distance
    if not np.isfinite(cost).any():
        cost[row, col] = 0.0
    return cost


def trace_path(
    parent: np.ndarray, nx: int, row: int, col: int, xmin: float, ymin: float, cell: float
) -> np.ndarray:
    """The cell centres (k, 2), m, from a search's source to (``row``, ``col``), by following ``parents`` (flat
    indices of a grid ``nx`` columns wide, as ``grid_paths`` returns them)."""
    cells = []
    u = row * nx + col
    while u >= 0:
        cells.append(u)
        u = int(parent[u])
    cells.reverse()
    rows, cols = np.divmod(np.array(cells, dtype=np.int64), nx)
    return np.column_stack([xmin + (cols + 0.5) * cell, ymin + (rows + 0.5) * cell])


@njit(cache=True)
def carrot(path, first, wall, xmin, ymin, cell, x, y, lookahead):
    """The index of the furthest point of ``path`` (k, 2) from index ``first`` on that lies within ``lookahead``
    m of (x, y) in a straight line the wall grid leaves free (at least ``first``): the point a path follower
    steers at."""
    best = first
    for i in range(first, path.shape[0]):
        dx, dy = path[i, 0] - x, path[i, 1] - y
        if dx * dx + dy * dy > lookahead * lookahead:
            break
        if line_is_free(wall, xmin, ymin, cell, x, y, path[i, 0], path[i, 1]):
            best = i
    return best
