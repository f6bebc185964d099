"""Estimation: motion and sensor models, EKF-SLAM, and (``graph``) least-squares SLAM."""

from .ekf import COURSE_MEASUREMENT_NOISE, COURSE_MOTION_NOISE, EKFSLAM, FilterDivergedError
from .models import (
    inverse_range_bearing,
    odometry_motion,
    range_bearing,
    velocity_motion,
    wrap_angle,
)

__all__ = [
    "COURSE_MEASUREMENT_NOISE",
    "COURSE_MOTION_NOISE",
    "EKFSLAM",
    "FilterDivergedError",
    "inverse_range_bearing",
    "odometry_motion",
    "range_bearing",
    "velocity_motion",
    "wrap_angle",
]
