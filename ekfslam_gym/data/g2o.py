"""g2o text graphs, 2-D subset: VERTEX_SE2, VERTEX_XY, EDGE_SE2, EDGE_SE2_XY.

    VERTEX_SE2  id x y theta
    VERTEX_XY   id x y
    EDGE_SE2    i j  dx dy dtheta  I11 I12 I13 I22 I23 I33   # upper triangle of the 3×3 information matrix
    EDGE_SE2_XY i j  lx ly         I11 I12 I22               # landmark j in the frame of pose i

Poses and landmarks keep the order in which their vertices appear; the first pose is the one the optimiser's gauge
holds. Blank lines and ``#`` comments are skipped; anything else that does not parse raises ``ValueError`` naming
the file and line.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from ..graph.optimizer import FactorGraph, GraphProblem, Values
from .records import read_records

__all__ = ["read_g2o", "write_g2o"]

_FIELDS = {"VERTEX_SE2": 4, "VERTEX_XY": 3, "EDGE_SE2": 11, "EDGE_SE2_XY": 7}  # values after the tag
_UPPER3 = (np.array([0, 0, 0, 1, 1, 2]), np.array([0, 1, 2, 1, 2, 2]))
_UPPER2 = (np.array([0, 0, 1]), np.array([0, 1, 1]))


def read_g2o(path: str | os.PathLike[str]) -> GraphProblem:
    """Read a 2-D g2o file into a graph, its initial values and the file's vertex ids."""
    path = Path(path)
    pose_index: dict[int, int] = {}
    landmark_index: dict[int, int] = {}
    poses: list[list[float]] = []
    landmarks: list[list[float]] = []
    between: list[tuple[int, int, int, list[float]]] = []  # (line, i, j, numbers)
    pose_landmark: list[tuple[int, int, int, list[float]]] = []

    def fail(line_no: int, message: str) -> ValueError:
        return ValueError(f"{path}:{line_no}: {message}")

    for record in read_records(path):
        fields, line_no = record.tokens, record.line
        tag = fields[0]
        if tag not in _FIELDS:
            raise record.error(f"unsupported tag {tag!r} (expected one of {', '.join(_FIELDS)})")
        record.expect(_FIELDS[tag], tag, tagged=True)
        try:
            ids = [int(f) for f in fields[1 : 2 if tag.startswith("VERTEX") else 3]]
            numbers = [float(f) for f in fields[1 + len(ids) :]]
        except ValueError as exc:
            raise record.error(f"malformed {tag} line: {exc}") from None
        if not all(math.isfinite(v) for v in numbers):
            raise record.error(f"{tag} has a non-finite value")
        if tag.startswith("VERTEX"):
            vid = ids[0]
            if vid in pose_index or vid in landmark_index:
                raise record.error(f"vertex {vid} defined twice")
            if tag == "VERTEX_SE2":
                pose_index[vid] = len(poses)
                poses.append(numbers)
            else:
                landmark_index[vid] = len(landmarks)
                landmarks.append(numbers)
        elif tag == "EDGE_SE2":
            between.append((line_no, ids[0], ids[1], numbers))
        else:
            pose_landmark.append((line_no, ids[0], ids[1], numbers))

    def resolve(line_no: int, vid: int, table: dict[int, int], what: str) -> int:
        if vid not in table:
            raise fail(line_no, f"edge refers to {vid}, which is not a {what} vertex")
        return table[vid]

    graph = FactorGraph()
    for edges, second_index, second_tag, (rows, cols), add in (
        (between, pose_index, "VERTEX_SE2", _UPPER3, graph.add_between),
        (pose_landmark, landmark_index, "VERTEX_XY", _UPPER2, graph.add_pose_landmark),
    ):
        if not edges:
            continue
        m = int(rows.max()) + 1  # the measurement's size: the information matrix is m x m
        i = [resolve(n, a, pose_index, "VERTEX_SE2") for n, a, _, _ in edges]
        j = [resolve(n, b, second_index, second_tag) for n, _, b, _ in edges]
        numbers = np.array([v for *_, v in edges])
        info = np.zeros((len(edges), m, m))
        info[:, rows, cols] = numbers[:, m:]
        info[:, cols, rows] = numbers[:, m:]
        add(i, j, numbers[:, :m], info)
    return GraphProblem(
        graph,
        Values(np.array(poses).reshape(-1, 3), np.array(landmarks).reshape(-1, 2)),
        np.array(list(pose_index), dtype=np.int64),
        np.array(list(landmark_index), dtype=np.int64),
    )


def write_g2o(
    path: str | os.PathLike[str],
    graph: FactorGraph,
    values: Values,
    pose_ids: np.ndarray | None = None,
    landmark_ids: np.ndarray | None = None,
) -> None:
    """Write poses, landmarks, pose-pose and pose-landmark edges; numbers round-trip exactly (17 digits).

    Ids default to 0…P−1 for poses and P…P+L−1 for landmarks. Range-bearing and prior factors have no tag in this
    subset of the format and raise ``ValueError``.
    """
    for kind in ("range_bearing", "prior"):
        if len(graph.factors(kind)):
            raise ValueError(f"g2o (2-D subset) cannot store {kind} factors")
    P, L = values.num_poses, values.num_landmarks
    pose_ids = np.arange(P) if pose_ids is None else np.asarray(pose_ids)
    landmark_ids = np.arange(P, P + L) if landmark_ids is None else np.asarray(landmark_ids)
    if len(pose_ids) != P or len(landmark_ids) != L:
        raise ValueError("pose_ids / landmark_ids do not match the number of poses / landmarks")
    lines = []
    for vid, (x, y, th) in zip(pose_ids.tolist(), values.poses.tolist()):
        lines.append(f"VERTEX_SE2 {vid} {x!r} {y!r} {th!r}")
    for vid, (x, y) in zip(landmark_ids.tolist(), values.landmarks.tolist()):
        lines.append(f"VERTEX_XY {vid} {x!r} {y!r}")
    for tag, f, second_ids, (rows, cols) in (
        ("EDGE_SE2", graph.between, pose_ids, _UPPER3),
        ("EDGE_SE2_XY", graph.pose_landmark, landmark_ids, _UPPER2),
    ):
        upper = f.information[:, rows, cols]
        for a, b, z, w in zip(
            pose_ids[f.first].tolist(), second_ids[f.second].tolist(), f.measured.tolist(), upper.tolist()
        ):
            lines.append(f"{tag} {a} {b} " + " ".join(repr(v) for v in z + w))
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
