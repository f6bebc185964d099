"""The robot-to-robot sensor model of a team: one robot reads another's position as range and bearing.

An observer at pose (x_i, y_i, theta_i) reads robot j's position (x_j, y_j) in its own frame, as the MRCLAM
robots read each other's barcodes (Leung et al., IJRR 2011): z = (range, bearing), the same reading as a point
landmark's, with the other robot's position in place of the landmark. The reading does not depend on j's
heading, so d z / d theta_j = 0. Compiled with numba (``cache=True``) for the team filter's kernels; a plain
callable from Python too (the finite-difference tests use it). Conventions as ``models``: metres, radians,
bearings wrapped to (-pi, pi].
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .models import range_bearing_into


@njit(cache=True)
def robot_range_bearing(observer: np.ndarray, target: np.ndarray, min_range: float):
    """Expected reading of robot ``target``'s position (x, y, theta) from robot ``observer`` (x, y, theta).

    Returns z = (range, bearing) (2,), H_observer = dz/d observer pose (2, 3) and H_target = dz/d target pose
    (2, 3), whose heading column is zero. Below ``min_range`` metres the Jacobians use ``min_range`` (as
    ``models.range_bearing``).
    """
    h_observer = np.empty((2, 3))
    h_position = np.empty((2, 2))
    z = np.empty(2)
    z[0], z[1] = range_bearing_into(observer, target[:2], min_range, h_observer, h_position)
    h_target = np.zeros((2, 3))
    h_target[:, :2] = h_position
    return z, h_observer, h_target
