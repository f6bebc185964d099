"""The rigid motion of the plane (SE(2): a rotation and a translation, no scale) that best lays one point set
on another, for judging a map whose frame is arbitrary.

A SLAM run without pose truth starts in its own frame (here the first pose is the origin), so its landmarks can
only be compared with surveyed ones after the least-squares alignment: Umeyama, "Least-squares estimation of
transformation parameters between two point patterns", IEEE PAMI 13(4), 1991, without the scale.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["SE2Transform", "align_se2"]


class SE2Transform(NamedTuple):
    """p -> R(angle) p + translation (angle rad, translation (2,) m)."""

    angle: float
    translation: np.ndarray

    @property
    def rotation(self) -> np.ndarray:
        c, s = math.cos(self.angle), math.sin(self.angle)
        return np.array([[c, -s], [s, c]])

    def points(self, xy: np.ndarray) -> np.ndarray:
        """The points (n, 2) moved."""
        return np.asarray(xy, dtype=float) @ self.rotation.T + self.translation

    def poses(self, poses: np.ndarray) -> np.ndarray:
        """The poses (n, 3) (x, y, heading) moved; headings turn by ``angle``, unwrapped."""
        poses = np.asarray(poses, dtype=float)
        return np.column_stack([self.points(poses[:, :2]), poses[:, 2] + self.angle])

    def covariances(self, covs: np.ndarray) -> np.ndarray:
        """Position covariances (n, 2, 2) expressed in the new frame: R C R^T."""
        rotation = self.rotation
        return rotation @ np.asarray(covs, dtype=float) @ rotation.T


def align_se2(source: np.ndarray, target: np.ndarray) -> SE2Transform:
    """The SE(2) transform T minimising sum_i |T(source_i) - target_i|^2 over (n, 2) point pairs, n >= 2."""
    source = np.asarray(source, dtype=float).reshape(-1, 2)
    target = np.asarray(target, dtype=float).reshape(-1, 2)
    if source.shape != target.shape or len(source) < 2:
        raise ValueError(f"need two (n, 2) point sets with n >= 2, got {source.shape} and {target.shape}")
    if not (np.all(np.isfinite(source)) and np.all(np.isfinite(target))):
        raise ValueError("points must be finite")
    mu_s, mu_t = source.mean(axis=0), target.mean(axis=0)
    a, b = source - mu_s, target - mu_t
    # In 2-D the optimal rotation is atan2 of the summed cross and dot products (Umeyama's SVD, written out).
    angle = math.atan2(float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])), float(np.sum(a * b)))
    c, s = math.cos(angle), math.sin(angle)
    translation = mu_t - np.array([[c, -s], [s, c]]) @ mu_s
    return SE2Transform(angle, translation)
