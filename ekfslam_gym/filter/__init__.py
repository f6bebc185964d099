"""The online filter: EKF-SLAM with its compiled kernels and its motion and sensor models (with Jacobians).

Knows nothing of the simulator or the env; ``ekfslam_gym.graph`` is the offline least-squares back end.
"""

from .ekf import COURSE_MEASUREMENT_NOISE, COURSE_MOTION_NOISE, EKFSLAM, FilterDivergedError, Jacobians
from .settings import COURSE_SETTINGS, AssociationSettings, FilterSettings

__all__ = [
    "AssociationSettings",
    "COURSE_MEASUREMENT_NOISE",
    "COURSE_MOTION_NOISE",
    "COURSE_SETTINGS",
    "EKFSLAM",
    "FilterDivergedError",
    "FilterSettings",
    "Jacobians",
    "inverse_range_bearing",
    "odometry_motion",
    "range_bearing",
    "velocity_motion",
    "wheel_motion",
    "wrap_angle",
]

_MODELS = (
    "inverse_range_bearing",
    "odometry_motion",
    "range_bearing",
    "velocity_motion",
    "wheel_motion",
    "wrap_angle",
)


def __getattr__(name: str):
    # The models are numba functions: loaded on first use, so that the env's start-up never loads numba.
    if name in _MODELS:
        from . import models

        return getattr(models, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
