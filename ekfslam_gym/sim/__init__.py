"""The simulator: layouts, a pymunk differential-drive robot, odometry and a range-bearing sensor.

It knows nothing of the filter; the env composes the two. Units are metres, seconds and radians.
"""

from .layouts import LAYOUTS, Layout, make_layout, place_landmarks
from .odometry import (
    OdometryNoise,
    OdometryReading,
    VelocityNoise,
    VelocityReading,
    WheelOdometryNoise,
    WheelOdometryReading,
    compose_odometry,
)
from .robot import RobotParams
from .sensor import RangeBearingSensor, Readings, SensorParams
from .world import World

__all__ = [
    "LAYOUTS",
    "Layout",
    "OdometryNoise",
    "OdometryReading",
    "RangeBearingSensor",
    "Readings",
    "RobotParams",
    "SensorParams",
    "VelocityNoise",
    "VelocityReading",
    "WheelOdometryNoise",
    "WheelOdometryReading",
    "World",
    "compose_odometry",
    "decompose_odometry",
    "decompose_wheels",
    "make_layout",
    "place_landmarks",
    "velocity_from_motion",
]


def __getattr__(name: str):
    # The compiled odometry helpers: loaded (with numba) on first use, never at import.
    if name in ("decompose_odometry", "decompose_wheels", "velocity_from_motion"):
        from . import odometry_kernels

        return getattr(odometry_kernels, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
