"""The graph files of the Freiburg *Robot Mapping* course (C. Stachniss), ``.dat``: MATLAB 5 MAT files written by
Octave.

Each file holds one struct ``g``: ``g.x`` (all states stacked: a pose is x y θ, a landmark x y), ``g.edges`` (type
'P' or 'L', from, to, measurement, information, fromIdx, toIdx with 1-based start indices into ``g.x``) and
``g.idLookup`` (one field per vertex id with its 0-based offset and dimension).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import scipy.io

from ..graph.optimizer import FactorGraph, GraphProblem, Values

__all__ = ["read_mat_graph"]


def read_mat_graph(path: str | os.PathLike[str]) -> GraphProblem:
    """Read a course ``.dat`` graph; poses and landmarks keep their order in ``g.x``."""
    path = Path(path)
    try:
        g = scipy.io.loadmat(path, squeeze_me=True, struct_as_record=False)["g"]
    except FileNotFoundError:
        raise
    except Exception as exc:  # scipy raises many kinds (MatReadError, IndexError, …) on foreign files
        raise ValueError(f"{path}: not a course graph file (MAT struct 'g'): {exc!r}") from None
    for name in ("x", "edges", "idLookup"):
        if not hasattr(g, name):
            raise ValueError(f"{path}: struct g has no field {name!r}")
    x = np.atleast_1d(np.asarray(g.x, dtype=float))

    # Vertices from idLookup, in the order of their offsets into g.x.
    lookup = g.idLookup
    vertex_ids = np.array([int(name) for name in lookup._fieldnames], dtype=np.int64)
    offsets = np.array([int(getattr(lookup, name).offset) for name in lookup._fieldnames], dtype=np.int64)
    dims = np.array([int(getattr(lookup, name).dimension) for name in lookup._fieldnames], dtype=np.int64)
    order = np.argsort(offsets, kind="stable")
    vertex_ids, offsets, dims = vertex_ids[order], offsets[order], dims[order]
    if not np.all(np.isin(dims, (2, 3))):
        raise ValueError(
            f"{path}: vertex dimensions must be 3 (pose) or 2 (landmark), got {sorted(set(dims))}"
        )
    ends = offsets + dims
    if offsets.size and (offsets[0] != 0 or np.any(offsets[1:] != ends[:-1]) or ends[-1] != x.size):
        raise ValueError(f"{path}: idLookup offsets do not tile g.x (size {x.size})")
    is_pose = dims == 3
    # An edge names its vertices by their offset into g.x; map offsets to pose / landmark indices.
    pose_at = dict(zip(offsets[is_pose].tolist(), range(int(is_pose.sum())), strict=True))
    landmark_at = dict(zip(offsets[~is_pose].tolist(), range(int((~is_pose).sum())), strict=True))

    poses = np.stack([x[o : o + 3] for o in offsets[is_pose]]) if is_pose.any() else np.zeros((0, 3))
    landmarks = np.stack([x[o : o + 2] for o in offsets[~is_pose]]) if (~is_pose).any() else np.zeros((0, 2))

    edges = np.atleast_1d(g.edges)
    # Per edge type: the table its second vertex is found in, the measurement's size, and the edges read
    # (first index, second index, measurement, information).
    second_at = {"P": pose_at, "L": landmark_at}
    edge_dim = {"P": 3, "L": 2}
    read: dict[str, list[tuple[int, int, np.ndarray, np.ndarray]]] = {"P": [], "L": []}
    for k, edge in enumerate(edges):
        try:
            kind = str(edge.type)
            from_offset, to_offset = int(edge.fromIdx) - 1, int(edge.toIdx) - 1  # 1-based in the file
            z = np.atleast_1d(np.asarray(edge.measurement, dtype=float))
            info = np.atleast_2d(np.asarray(edge.information, dtype=float))
        except AttributeError as exc:
            raise ValueError(f"{path}: edge {k + 1}: missing field ({exc})") from None
        if kind not in read:
            raise ValueError(f"{path}: edge {k + 1} has unknown type {kind!r} (expected 'P' or 'L')")
        m = edge_dim[kind]
        if (
            from_offset not in pose_at
            or to_offset not in second_at[kind]
            or z.shape != (m,)
            or info.shape != (m, m)
        ):
            raise ValueError(f"{path}: edge {k + 1} (type {kind}) is malformed")
        read[kind].append((pose_at[from_offset], second_at[kind][to_offset], z, info))

    graph = FactorGraph()
    for kind, add in (("P", graph.add_between), ("L", graph.add_pose_landmark)):
        if read[kind]:
            first, second, z, info = zip(*read[kind], strict=True)
            add(list(first), list(second), np.array(z), np.array(info))
    return GraphProblem(graph, Values(poses, landmarks), vertex_ids[is_pose], vertex_ids[~is_pose])
