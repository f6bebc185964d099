"""GTSAM's 2-D dataset text format, read as GTSAM's ``load2D`` reads it (gtsam/slam/dataset.cpp, GTSAM 4.2-4.3).

One line per item, the tag first; ids are non-negative integers, poses and landmarks have separate id spaces
(GTSAM keys landmarks as ``L(id)``)::

    VERTEX_SE2 id x y theta          (also VERTEX2, VERTEX)   initial value of a pose
    VERTEX_XY  id x y                                         initial value of a landmark
    ODOMETRY i j  dx dy dtheta  v1 v2 v3 v4 v5 v6  (also EDGE2, EDGE, EDGE_SE2)  pose j relative to pose i
    LANDMARK i l  x y  v1 v2 v3      landmark l seen from pose i at (x, y) in its frame
    BR       i l  bearing range  bearing_std range_std

The six noise values of an edge are read by `noise_format`, GTSAM's ``NoiseFormat``:

- ``"cov"``: the covariance's upper triangle row by row, (xx xy xθ yy yθ θθ);
- ``"g2o"``: the information matrix in that order;
- ``"graph"``: the covariance in TORO's order, (xx xy yy θθ xθ yθ);
- ``"toro"``: the information matrix in TORO's order;
- ``"auto"`` (``load2D``'s default): per line, a diagonal matrix whose zeros sit where ``"graph"`` puts its
  off-diagonal terms is ``"graph"``, one whose zeros sit where ``"cov"`` puts them is ``"cov"``; anything else is
  an error. Victoria Park's ``0.0001 0 0 4e-06 0 4e-06`` is ``"cov"``: diag(1e-4, 4e-6, 4e-6) in (x, y, θ).

A LANDMARK line becomes a bearing-range reading as in GTSAM: bearing = atan2(y, x), range = |(x, y)|, and
when v1 and v3 agree (to 1e-4) the sigmas are sqrt(v1 / 10) rad for the bearing and sqrt(v1) m for the range
("assume it describes the uncertainty at a range of 10 m"); otherwise GTSAM ignores the covariance and uses 1
and 1, and so does this reader, with a warning.

Initial values follow ``load2D`` too: VERTEX lines first, wherever they are; then, in file order, an edge whose
first pose has no value puts it at the origin and one whose second pose has none composes it from the first, and
a reading whose landmark has none places it from the pose it is seen from. Malformed lines raise ``ValueError``
naming the file and line (GTSAM would skip unknown tags; this reader refuses them).
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..graph.optimizer import FactorGraph, GraphProblem, Values
from .records import read_records

__all__ = ["NOISE_FORMATS", "Gtsam2dDataset", "read_gtsam2d"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

NOISE_FORMATS = ("auto", "cov", "g2o", "graph", "toro")

_POSE_VERTEX = ("VERTEX_SE2", "VERTEX2", "VERTEX")
_EDGE = ("ODOMETRY", "EDGE_SE2", "EDGE2", "EDGE")
# How many fields follow each tag: (how many of them are ids, how many numbers).
_FIELDS = {
    **{tag: (1, 3) for tag in _POSE_VERTEX},
    "VERTEX_XY": (1, 2),
    **{tag: (2, 9) for tag in _EDGE},
    "LANDMARK": (2, 5),
    "BR": (2, 4),
}
# Where each of the six noise values goes in the 3x3 matrix, per layout (GTSAM's createNoiseModel).
_G2O_ORDER = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
_TORO_ORDER = ((0, 0), (0, 1), (1, 1), (2, 2), (0, 2), (1, 2))
# GTSAM's rule for LANDMARK covariances: v1 == v3 within this tolerance means "isotropic at 10 m".
_ISOTROPIC_TOLERANCE = 1e-4


@dataclass(frozen=True, eq=False)  # holds arrays
class Gtsam2dDataset:
    """A GTSAM 2-D file as arrays: initial values, odometry edges and bearing-range readings, in file order.

    Poses are indexed 0..P-1 in increasing file id (``pose_ids[p]`` is pose p's id), landmarks 0..L-1 likewise;
    edges and readings refer to those indices. Covariances are in the measurement's own order: (x, y, θ) for an
    edge, (range, bearing) for a reading. ``*_lines`` give each item's line in the file.
    """

    path: Path
    pose_ids: IntArray  # (P,)
    poses: Array  # (P, 3) initial values: x [m], y [m], θ [rad]
    landmark_ids: IntArray  # (L,)
    landmarks: Array  # (L, 2) initial values [m]
    edge_first: IntArray  # (E,) pose index
    edge_second: IntArray  # (E,) pose index
    edge_measured: Array  # (E, 3) pose second in the frame of pose first: dx [m], dy [m], dθ [rad]
    edge_covariance: Array  # (E, 3, 3)
    edge_lines: IntArray  # (E,)
    reading_pose: IntArray  # (R,) pose index
    reading_landmark: IntArray  # (R,) landmark index
    reading: Array  # (R, 2) range [m], bearing [rad]
    reading_covariance: Array  # (R, 2, 2) diag(σ_range², σ_bearing²)
    reading_lines: IntArray  # (R,)

    @property
    def num_poses(self) -> int:
        return len(self.pose_ids)

    @property
    def num_landmarks(self) -> int:
        return len(self.landmark_ids)

    def readings_at(self, pose: int) -> IntArray:
        """Indices of the readings taken from pose index `pose`, in file order."""
        return np.flatnonzero(self.reading_pose == pose)

    def to_problem(self) -> GraphProblem:
        """The factor graph (between edges and range-bearing factors) with this file's initial values.

        No prior is added: the optimisers hold the first pose (the smallest id) when a graph has none.
        """
        graph = FactorGraph()
        if len(self.edge_first):
            graph.add_between(
                self.edge_first,
                self.edge_second,
                self.edge_measured,
                np.linalg.inv(self.edge_covariance),
            )
        if len(self.reading_pose):
            information = np.zeros_like(self.reading_covariance)
            information[:, [0, 1], [0, 1]] = 1.0 / self.reading_covariance[:, [0, 1], [0, 1]]
            graph.add_range_bearing(self.reading_pose, self.reading_landmark, self.reading, information)
        return GraphProblem(
            graph, Values(self.poses, self.landmarks), self.pose_ids.copy(), self.landmark_ids.copy()
        )


def _noise_matrix(values: list[float], noise_format: str, fail) -> Array:
    """The 3x3 covariance of an edge's six noise values, read as GTSAM reads them for `noise_format`."""
    v = values
    if noise_format == "auto":
        if v[0] != 0 and v[1] == 0 and v[2] != 0 and v[3] != 0 and v[4] == 0 and v[5] == 0:
            noise_format = "graph"
        elif v[0] != 0 and v[1] == 0 and v[2] == 0 and v[3] != 0 and v[4] == 0 and v[5] != 0:
            noise_format = "cov"
        else:
            raise fail(
                "cannot tell the layout of the six noise values (GTSAM's automatic detection knows only "
                "diagonal covariances in COV or GRAPH order); pass noise_format='cov', 'g2o', 'graph' or 'toro'"
            )
    order = _G2O_ORDER if noise_format in ("cov", "g2o") else _TORO_ORDER
    M = np.zeros((3, 3))
    for value, (r, c) in zip(v, order, strict=True):
        M[r, c] = M[c, r] = value
    if np.any(np.diag(M) == 0):
        raise fail(f"a zero on the diagonal of the noise matrix read as {noise_format!r}")
    if noise_format in ("g2o", "toro"):  # the file holds the information matrix
        try:
            M = np.linalg.inv(M)
        except np.linalg.LinAlgError:
            raise fail(f"singular information matrix (read as {noise_format!r})") from None
    if np.any(np.linalg.eigvalsh(M) <= 0):
        raise fail(f"the noise matrix read as {noise_format!r} is not positive definite: {v}")
    return M


def read_gtsam2d(path: str | os.PathLike[str], noise_format: str = "auto") -> Gtsam2dDataset:
    """Read a GTSAM 2-D dataset file (see the module docstring); `noise_format` is one of `NOISE_FORMATS`."""
    if noise_format not in NOISE_FORMATS:
        raise ValueError(f"unknown noise_format {noise_format!r}; expected one of {NOISE_FORMATS}")
    path = Path(path)
    pose_vertices: dict[int, tuple[float, float, float]] = {}
    landmark_vertices: dict[int, tuple[float, float]] = {}
    edges: list[tuple[int, int, int, tuple[float, ...], Array]] = []  # line, i, j, (dx, dy, dθ), covariance
    readings: list[tuple[int, int, int, float, float, float, float]] = []  # line, i, l, r, φ, σr, σφ
    order: list[tuple[str, int]] = []  # ("edge" | "reading", position), in file order
    warned_anisotropic = False
    noise_cache: dict[tuple[float, ...], Array] = {}  # files tend to repeat one noise line: read each once

    for record in read_records(path):
        fields, line_no, fail = record.tokens, record.line, record.error
        tag = fields[0]
        if tag not in _FIELDS:
            raise fail(f"unknown tag {tag!r} (expected one of {', '.join(_FIELDS)})")
        n_ids, n_numbers = _FIELDS[tag]
        record.expect(n_ids + n_numbers, tag, tagged=True)
        try:
            ids = [int(f) for f in fields[1 : 1 + n_ids]]
        except ValueError:
            raise fail(f"{tag} ids must be integers, got {' '.join(fields[1 : 1 + n_ids])}") from None
        if any(i < 0 for i in ids):
            raise fail(f"{tag} ids must be non-negative, got {' '.join(fields[1 : 1 + n_ids])}")
        try:
            numbers = [float(f) for f in fields[1 + n_ids :]]
        except ValueError as exc:
            raise fail(f"malformed {tag} line: {exc}") from None
        if not all(math.isfinite(v) for v in numbers):
            raise fail(f"{tag} has a non-finite value")

        if tag in _POSE_VERTEX or tag == "VERTEX_XY":
            table = pose_vertices if tag in _POSE_VERTEX else landmark_vertices
            if ids[0] in table:
                raise fail(f"{'pose' if table is pose_vertices else 'landmark'} {ids[0]} defined twice")
            table[ids[0]] = tuple(numbers)  # type: ignore[assignment]
        elif tag in _EDGE:
            if ids[0] == ids[1]:
                raise fail(f"{tag} from pose {ids[0]} to itself")
            key = tuple(numbers[3:])
            if key not in noise_cache:
                noise_cache[key] = _noise_matrix(numbers[3:], noise_format, fail)
            covariance = noise_cache[key]
            order.append(("edge", len(edges)))
            edges.append((line_no, ids[0], ids[1], tuple(numbers[:3]), covariance))
        else:
            if tag == "BR":
                bearing, rng, bearing_std, range_std = numbers
                if bearing_std <= 0 or range_std <= 0:
                    raise fail("BR standard deviations must be positive")
            else:  # LANDMARK
                x, y, v1, _, v3 = numbers
                bearing, rng = math.atan2(y, x), math.hypot(x, y)
                if abs(v1 - v3) < _ISOTROPIC_TOLERANCE:
                    if v1 <= 0:
                        raise fail(f"LANDMARK variance must be positive, got {v1}")
                    bearing_std, range_std = math.sqrt(v1 / 10.0), math.sqrt(v1)
                else:
                    bearing_std = range_std = 1.0
                    if not warned_anisotropic:
                        warnings.warn(
                            f"{record.where}: LANDMARK covariance is not isotropic; like GTSAM's load2D, "
                            "the reader ignores it and uses unit sigmas",
                            stacklevel=2,
                        )
                        warned_anisotropic = True
            order.append(("reading", len(readings)))
            readings.append((line_no, ids[0], ids[1], rng, bearing, range_std, bearing_std))

    # Initial values in file order, as load2D inserts them.
    pose_values: dict[int, tuple[float, float, float]] = dict(pose_vertices)
    landmark_values: dict[int, tuple[float, float]] = dict(landmark_vertices)
    for what, k in order:
        if what == "edge":
            _, i, j, (dx, dy, dth), _ = edges[k]
            xi, yi, thi = pose_values.setdefault(i, (0.0, 0.0, 0.0))
            if j not in pose_values:
                c, s = math.cos(thi), math.sin(thi)
                heading = math.atan2(math.sin(thi + dth), math.cos(thi + dth))
                pose_values[j] = (xi + c * dx - s * dy, yi + s * dx + c * dy, heading)
        else:
            _, i, lm, rng, bearing, _, _ = readings[k]
            xi, yi, thi = pose_values.setdefault(i, (0.0, 0.0, 0.0))
            if lm not in landmark_values:
                landmark_values[lm] = (xi + rng * math.cos(thi + bearing), yi + rng * math.sin(thi + bearing))

    if not pose_values:
        raise ValueError(f"{path}: no poses (no VERTEX, ODOMETRY/EDGE, LANDMARK or BR line)")
    pose_ids = np.array(sorted(pose_values), dtype=np.int64)
    landmark_ids = np.array(sorted(landmark_values), dtype=np.int64)
    pose_index = {int(v): k for k, v in enumerate(pose_ids)}
    landmark_index = {int(v): k for k, v in enumerate(landmark_ids)}

    sigmas = np.array([r[5:7] for r in readings], dtype=float).reshape(-1, 2)  # σ_range, σ_bearing

    def column(rows: list, k: int, dtype: type = float) -> np.ndarray:
        return np.array([row[k] for row in rows], dtype=dtype)

    return Gtsam2dDataset(
        path=path,
        pose_ids=pose_ids,
        poses=np.array([pose_values[i] for i in pose_ids.tolist()], dtype=float).reshape(-1, 3),
        landmark_ids=landmark_ids,
        landmarks=np.array([landmark_values[i] for i in landmark_ids.tolist()], dtype=float).reshape(-1, 2),
        edge_first=np.array([pose_index[e[1]] for e in edges], dtype=np.int64),
        edge_second=np.array([pose_index[e[2]] for e in edges], dtype=np.int64),
        edge_measured=np.array([e[3] for e in edges], dtype=float).reshape(-1, 3),
        edge_covariance=np.array([e[4] for e in edges], dtype=float).reshape(-1, 3, 3),
        edge_lines=column(edges, 0, np.int64),
        reading_pose=np.array([pose_index[r[1]] for r in readings], dtype=np.int64),
        reading_landmark=np.array([landmark_index[r[2]] for r in readings], dtype=np.int64),
        reading=np.array([(r[3], r[4]) for r in readings], dtype=float).reshape(-1, 2),
        reading_covariance=np.einsum("ri,ij->rij", sigmas**2, np.eye(2)),
        reading_lines=column(readings, 0, np.int64),
    )
