"""Error functions of the graph's edge types with their Jacobians, vectorised over edges.

Layout: component first. A stack of E poses is a (3, E) array, E landmarks (2, E), E measurements (m, E); an error
is (m, E) and a Jacobian (m, d, E) with d the summed dimension of the edge's variables in order (first, second).
Each row is then a contiguous vector over edges, which is what makes the per-edge arithmetic fast in numpy.

Convention (the course's): e = f(x) − z style errors and J = ∂e/∂x, so the Gauss-Newton step is Δx = −H⁻¹ b.
Angular error components are wrapped to (−π, π].
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..angles import wrap_angles

__all__ = [
    "FACTOR_KINDS",
    "FactorKind",
    "between_error",
    "between_linearize",
    "landmark_from_range_bearing",
    "pose_landmark_error",
    "pose_landmark_linearize",
    "prior_error",
    "prior_linearize",
    "range_bearing",
    "range_bearing_error",
    "range_bearing_linearize",
]

Array = NDArray[np.float64]

# Below this range [m] the bearing is undefined; clamping keeps the Jacobian finite.
_MIN_RANGE = 1e-9


def between_error(pose_i: Array, pose_j: Array, measured: Array) -> Array:
    """Pose-pose error e_ij = t2v(Z_ij⁻¹ (X_i⁻¹ X_j)), shape (3, E)."""
    ci, si = np.cos(pose_i[2]), np.sin(pose_i[2])
    dx, dy = pose_j[0] - pose_i[0], pose_j[1] - pose_i[1]
    u = ci * dx + si * dy - measured[0]
    v = -si * dx + ci * dy - measured[1]
    cz, sz = np.cos(measured[2]), np.sin(measured[2])
    return np.stack([cz * u + sz * v, -sz * u + cz * v, wrap_angles(pose_j[2] - pose_i[2] - measured[2])])


def between_linearize(pose_i: Array, pose_j: Array, measured: Array) -> tuple[Array, Array]:
    """Pose-pose error (3, E) and its Jacobian w.r.t. (x_i, x_j), shape (3, 6, E).

    With R = R_zᵀ R_iᵀ: ∂e_t/∂t_i = −R, ∂e_t/∂θ_i = R_zᵀ (∂R_iᵀ/∂θ)(t_j − t_i), ∂e_t/∂t_j = R, ∂e_θ/∂θ = ∓1.
    """
    ci, si = np.cos(pose_i[2]), np.sin(pose_i[2])
    dx, dy = pose_j[0] - pose_i[0], pose_j[1] - pose_i[1]
    u0 = ci * dx + si * dy
    v0 = -si * dx + ci * dy
    u, v = u0 - measured[0], v0 - measured[1]
    cz, sz = np.cos(measured[2]), np.sin(measured[2])
    # R = R(θ_i + θ_z)ᵀ, from the angle-sum identities rather than two more trigonometric calls.
    c = ci * cz - si * sz
    s = si * cz + ci * sz
    E = pose_i.shape[1]
    e = np.empty((3, E))
    e[0] = cz * u + sz * v
    e[1] = -sz * u + cz * v
    e[2] = wrap_angles(pose_j[2] - pose_i[2] - measured[2])
    J = np.zeros((3, 6, E))
    J[0, 0], J[0, 1], J[0, 2] = -c, -s, cz * v0 - sz * u0
    J[1, 0], J[1, 1], J[1, 2] = s, -c, -sz * v0 - cz * u0
    J[2, 2] = -1.0
    J[0, 3], J[0, 4] = c, s
    J[1, 3], J[1, 4] = -s, c
    J[2, 5] = 1.0
    return e, J


def pose_landmark_error(pose: Array, landmark: Array, measured: Array) -> Array:
    """Pose-landmark error e_il = R_iᵀ (x_l − t_i) − z_il, shape (2, E)."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    dx, dy = landmark[0] - pose[0], landmark[1] - pose[1]
    return np.stack([c * dx + s * dy - measured[0], -s * dx + c * dy - measured[1]])


def pose_landmark_linearize(pose: Array, landmark: Array, measured: Array) -> tuple[Array, Array]:
    """Pose-landmark error (2, E) and its Jacobian w.r.t. (x_i, x_l), shape (2, 5, E)."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    dx, dy = landmark[0] - pose[0], landmark[1] - pose[1]
    u0 = c * dx + s * dy
    v0 = -s * dx + c * dy
    e = np.stack([u0 - measured[0], v0 - measured[1]])
    J = np.empty((2, 5, pose.shape[1]))
    J[0, 0], J[0, 1], J[0, 2], J[0, 3], J[0, 4] = -c, -s, v0, c, s
    J[1, 0], J[1, 1], J[1, 2], J[1, 3], J[1, 4] = s, -c, -u0, -s, c
    return e, J


def range_bearing(pose: Array, landmark: Array) -> Array:
    """Predicted reading (range [m], bearing [rad] in (−π, π]) of landmarks seen from poses, shape (2, E)."""
    dx, dy = landmark[0] - pose[0], landmark[1] - pose[1]
    return np.stack([np.hypot(dx, dy), wrap_angles(np.arctan2(dy, dx) - pose[2])])


def landmark_from_range_bearing(pose: Array, reading: Array) -> Array:
    """Inverse sensor model: landmark positions (2, E) of readings (r, φ) taken from poses."""
    heading = pose[2] + reading[1]
    return np.stack([pose[0] + reading[0] * np.cos(heading), pose[1] + reading[0] * np.sin(heading)])


def range_bearing_error(pose: Array, landmark: Array, measured: Array) -> Array:
    """Range-bearing error (r̂ − r, wrap(φ̂ − φ)), shape (2, E)."""
    dx, dy = landmark[0] - pose[0], landmark[1] - pose[1]
    return np.stack([np.hypot(dx, dy) - measured[0], wrap_angles(np.arctan2(dy, dx) - pose[2] - measured[1])])


def range_bearing_linearize(pose: Array, landmark: Array, measured: Array) -> tuple[Array, Array]:
    """Range-bearing error (2, E) and its Jacobian w.r.t. (x_i, x_l), shape (2, 5, E).

    With d = x_l − t_i, q = |d|², r = √q: ∂r/∂x_l = dᵀ/r, ∂φ/∂x_l = (−d_y, d_x)/q, ∂φ/∂θ_i = −1, and the
    derivatives w.r.t. t_i are the negatives of those w.r.t. x_l.
    """
    dx, dy = landmark[0] - pose[0], landmark[1] - pose[1]
    q = np.maximum(dx * dx + dy * dy, _MIN_RANGE**2)
    r = np.sqrt(q)
    e = np.stack([r - measured[0], wrap_angles(np.arctan2(dy, dx) - pose[2] - measured[1])])
    ar, br = dx / r, dy / r
    aq, bq = dx / q, dy / q
    J = np.empty((2, 5, pose.shape[1]))
    J[0, 0], J[0, 1], J[0, 2], J[0, 3], J[0, 4] = -ar, -br, 0.0, ar, br
    J[1, 0], J[1, 1], J[1, 2], J[1, 3], J[1, 4] = bq, -aq, -1.0, -bq, aq
    return e, J


def prior_error(pose: Array, measured: Array) -> Array:
    """Pose prior error t2v(Z⁻¹ X), shape (3, E): the pose-pose error with X_i the origin."""
    cz, sz = np.cos(measured[2]), np.sin(measured[2])
    dx, dy = pose[0] - measured[0], pose[1] - measured[1]
    return np.stack([cz * dx + sz * dy, -sz * dx + cz * dy, wrap_angles(pose[2] - measured[2])])


def prior_linearize(pose: Array, measured: Array) -> tuple[Array, Array]:
    """Pose prior error (3, E) and its Jacobian w.r.t. x, shape (3, 3, E): blockdiag(R_zᵀ, 1)."""
    cz, sz = np.cos(measured[2]), np.sin(measured[2])
    J = np.zeros((3, 3, pose.shape[1]))
    J[0, 0], J[0, 1] = cz, sz
    J[1, 0], J[1, 1] = -sz, cz
    J[2, 2] = 1.0
    return prior_error(pose, measured), J


class FactorKind(NamedTuple):
    """How the graph treats one edge type: error size, what the second variable is, and its kernels."""

    dim: int  # dimension of the error
    second: str | None  # "pose", "landmark", or None for unary factors; the first variable is always a pose
    error: Callable[..., Array]
    linearize: Callable[..., tuple[Array, Array]]


FACTOR_KINDS: dict[str, FactorKind] = {
    "between": FactorKind(3, "pose", between_error, between_linearize),
    "pose_landmark": FactorKind(2, "landmark", pose_landmark_error, pose_landmark_linearize),
    "range_bearing": FactorKind(2, "landmark", range_bearing_error, range_bearing_linearize),
    "prior": FactorKind(3, None, prior_error, prior_linearize),
}
