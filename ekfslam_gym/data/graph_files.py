"""Pose-graph files by extension: the course's MAT ``.dat`` graphs and 2-D g2o text files."""

from __future__ import annotations

import os
from pathlib import Path

from ..graph.optimizer import GraphProblem


def read_graph(path: str | os.PathLike[str]) -> GraphProblem:
    """Read a graph file, choosing the format by extension (``.dat`` MAT or ``.g2o`` text)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".dat":
        from .matfile import read_mat_graph

        return read_mat_graph(path)
    if suffix == ".g2o":
        from .g2o import read_g2o

        return read_g2o(path)
    raise ValueError(f"{path}: unknown graph format {suffix!r} (expected .dat or .g2o)")
