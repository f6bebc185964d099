"""The Gymnasium environment: configuration, observation, rendering and the env that composes them."""

from .config import EnvConfig, FilterConfig, ObservationConfig, RewardConfig, WorldConfig
from .ekfslam_env import EKFSLAMEnv
from .presets import PRESETS

__all__ = [
    "EKFSLAMEnv",
    "EnvConfig",
    "FilterConfig",
    "ObservationConfig",
    "PRESETS",
    "RewardConfig",
    "WorldConfig",
]
