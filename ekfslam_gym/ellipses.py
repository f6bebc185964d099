"""Uncertainty ellipses of 2x2 covariances, the one implementation the renderer and the plots both draw."""

from __future__ import annotations

import numpy as np

SIGMAS = 3.0  # ellipses at 3 sigma, as in the Freiburg Robot Mapping course's EKF-SLAM figure


def ellipse_points(
    centres: np.ndarray, covs: np.ndarray, sigmas: float = SIGMAS, n: int = 24
) -> tuple[np.ndarray, np.ndarray]:
    """Polygons of the ``sigmas`` ellipses of 2x2 covariances, all at once.

    Returns ``(points, valid)``: points ``(len(covs), n, 2)`` in the centres' units and a mask of the
    covariances that make an ellipse (finite, positive semidefinite once symmetrised, not all zero), so a
    filter's bad or degenerate block is skipped instead of crashing the frame or drawing garbage.
    """
    centres = np.asarray(centres, dtype=float).reshape(-1, 2)
    covs = np.asarray(covs, dtype=float).reshape(-1, 2, 2)
    points = np.zeros((len(covs), n, 2))
    valid = np.isfinite(covs).all(axis=(1, 2)) & np.isfinite(centres).all(axis=1)
    if not valid.any():
        return points, valid
    sym = 0.5 * (covs[valid] + np.swapaxes(covs[valid], 1, 2))
    values, vectors = np.linalg.eigh(sym)  # ascending, per covariance
    scale = np.abs(values).max(axis=1)
    ok = (scale > 0) & (values[:, 0] >= -1e-9 * scale)
    idx = np.flatnonzero(valid)
    valid[idx[~ok]] = False
    radii = sigmas * np.sqrt(np.clip(values[ok], 0.0, None))  # (v, 2) semi-axes
    angles = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    circle = np.stack([np.cos(angles), np.sin(angles)], axis=1)  # (n, 2)
    # x = c + V diag(r) u for each unit-circle point u
    points[idx[ok]] = centres[idx[ok], None, :] + np.einsum("vij,vj,nj->vni", vectors[ok], radii, circle)
    return points, valid
