"""The frontiers of the unexplored on a coverage grid (Yamauchi 1997): cells not looked at that border looked-at
ones, grouped into 8-connected regions, and the greedy planner's distance field to the unexplored. Grid
convention: ``ekfslam_gym.agents.navigation``."""

from __future__ import annotations

import numpy as np

from .paths import distance_field

EIGHT_NEIGHBOURS = np.ones((3, 3), dtype=bool)


def frontier_cells(memory: np.ndarray, blocked: np.ndarray) -> np.ndarray:
    """Frontier cells (bool, the memory's shape) of a coverage ``memory`` (> 0: looked at): not looked at, not
    ``blocked`` (bool, e.g. walls), with a looked-at 4-neighbour."""
    looked = np.asarray(memory) > 0
    near = np.zeros_like(looked)
    near[1:, :] |= looked[:-1, :]
    near[:-1, :] |= looked[1:, :]
    near[:, 1:] |= looked[:, :-1]
    near[:, :-1] |= looked[:, 1:]
    return near & ~looked & ~np.asarray(blocked, dtype=bool)


def frontier_regions(frontier: np.ndarray, min_size: int) -> np.ndarray:
    """The ``frontier`` cells (bool grid) in 8-connected regions of at least ``min_size`` cells (bool, same
    shape): slivers along walls dropped."""
    from scipy import ndimage

    labels, count = ndimage.label(frontier, structure=EIGHT_NEIGHBOURS)
    if count == 0:
        return np.zeros_like(frontier, dtype=bool)
    sizes = np.bincount(labels.ravel())
    keep = sizes >= min_size
    keep[0] = False
    return keep[labels]


def frontier_field(
    open_cells: np.ndarray, wall: np.ndarray, cell: float, frontier_scale: float
) -> np.ndarray:
    """Distance (m) to the unexplored, around remembered walls, plus a cost for thin regions: every open
    unlooked-at cell (``open_cells``, bool grid) is a source with cost -frontier_scale * ln(the fraction of open
    cells in the surrounding 4 m), so a large unexplored region beats a nearer sliver along a wall."""
    from scipy import ndimage

    width = max(1, int(round(4.0 / cell)))
    density = ndimage.uniform_filter(open_cells.astype(float), size=width, mode="constant")
    start = np.where(open_cells, -frontier_scale * np.log(np.maximum(density, 1e-3)), np.inf)
    return distance_field(start, wall, cell, 64)
