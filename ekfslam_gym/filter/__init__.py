"""The online filter: EKF-SLAM with its compiled kernels and its motion and sensor models (with Jacobians).

Knows nothing of the simulator or the env; ``ekfslam_gym.graph`` is the offline least-squares back end.
"""

from .ekf import COURSE_MEASUREMENT_NOISE, COURSE_MOTION_NOISE, EKFSLAM, FilterDivergedError
from .models import inverse_range_bearing, odometry_motion, range_bearing, velocity_motion, wrap_angle

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
