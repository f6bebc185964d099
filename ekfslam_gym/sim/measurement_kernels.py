"""One compiled call for a step's wheel odometry and the noise of its landmark readings (the env's hot path).

The two readings are independent; fusing them saves a kernel call, a random draw and an array per step. The
values are those of ``odometry_kernels.sensed_wheel_reading`` followed by ``geometry.add_reading_noise``.
"""

from __future__ import annotations

from numba import njit

from ..kernel_types import F8Array1, F8Array2
from .geometry import add_reading_noise
from .odometry_kernels import sensed_wheel_reading


@njit(cache=True)
def measure_step(
    x0: float,
    y0: float,
    theta0: float,
    x1: float,
    y1: float,
    theta1: float,
    wheel_base: float,
    contact_travel: float,
    params: F8Array1,
    normals: F8Array1,
    u: F8Array1,
    cov: F8Array2,
    u_true: F8Array1,
    z: F8Array2,
    range_std: float,
    bearing_std: float,
) -> None:
    """Sensed-slide wheel odometry from pose 0 to pose 1 into (``u``, ``cov``, ``u_true``) with ``normals[:3]``,
    then the readings ``z`` (m, 2) made noisy in place with ``normals[3:]`` read as (m, 2) row by row."""
    sensed_wheel_reading(
        x0, y0, theta0, x1, y1, theta1, wheel_base, contact_travel, params, normals, u, cov, u_true
    )
    m = z.shape[0]
    if m:
        add_reading_noise(z, normals[3:].reshape(m, 2), range_std, bearing_std)
