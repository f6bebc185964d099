"""The simulator: layouts, a pymunk differential-drive robot, odometry and a range-bearing sensor.

It knows nothing of the filter; the env composes the two. Units are metres, seconds and radians.
"""

from .families import FAMILIES, TIERS, world_section
from .layouts import LAYOUTS, Layout, check_layout_kwargs, layout_keywords, make_layout, place_landmarks
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
    "FAMILIES",
    "LAYOUTS",
    "Layout",
    "OdometryNoise",
    "OdometryReading",
    "RangeBearingSensor",
    "Readings",
    "RobotParams",
    "SensorParams",
    "TIERS",
    "VelocityNoise",
    "VelocityReading",
    "WheelOdometryNoise",
    "WheelOdometryReading",
    "World",
    "check_layout_kwargs",
    "compose_odometry",
    "decompose_odometry",
    "decompose_wheels",
    "layout_keywords",
    "make_layout",
    "place_landmarks",
    "velocity_from_motion",
    "world_section",
]


def __getattr__(name: str):
    # The compiled odometry helpers: loaded (with numba) on first use, never at import.
    if name in ("decompose_odometry", "decompose_wheels", "velocity_from_motion"):
        from . import odometry_kernels

        return getattr(odometry_kernels, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
