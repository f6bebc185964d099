"""Pose-graph files by extension: the course's MAT ``.dat`` graphs, 2-D g2o text files and GTSAM's 2-D dataset
text files (``.txt`` / ``.graph``, as GTSAM's examples name them)."""

from __future__ import annotations

import os
from pathlib import Path

from ..graph.optimizer import GraphProblem

GTSAM_SUFFIXES = (".txt", ".graph")


def read_graph(path: str | os.PathLike[str]) -> GraphProblem:
    """Read a graph file, choosing the format by extension (``.dat`` MAT, ``.g2o``, or GTSAM ``.txt``/``.graph``)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".dat":
        from .matfile import read_mat_graph

        return read_mat_graph(path)
    if suffix == ".g2o":
        from .g2o import read_g2o

        return read_g2o(path)
    if suffix in GTSAM_SUFFIXES:
        from .gtsam2d import read_gtsam2d

        return read_gtsam2d(path).to_problem()
    raise ValueError(
        f"{path}: unknown graph format {suffix!r} (expected .dat, .g2o, or GTSAM's 2-D .txt / .graph)"
    )
