"""The Gymnasium environment: configuration, observation, rendering and the env that composes them."""

from .config import EnvConfig, FilterConfig, ObservationConfig, RewardConfig, WorldConfig
from .ekfslam_env import EKFSLAMEnv
from .horizon import HorizonSync
from .observation import ObservationLayout
from .presets import PRESETS
from .rewards import REWARD_TERMS

__all__ = [
    "EKFSLAMEnv",
    "EnvConfig",
    "FilterConfig",
    "HorizonSync",
    "ObservationConfig",
    "ObservationLayout",
    "PRESETS",
    "REWARD_TERMS",
    "RewardConfig",
    "WorldConfig",
]
