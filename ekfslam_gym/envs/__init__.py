"""The Gymnasium environment: configuration, observation, rewards, rendering and the env that composes them.

The names below are imported on first use, so that registering the ids (``import ekfslam_gym``) does not load
the simulator and the filter.
"""

from __future__ import annotations

import importlib

_HOMES = {
    "EKFSLAMEnv": "ekfslam_env",
    "ActionConfig": "config",
    "EnvConfig": "config",
    "FilterConfig": "config",
    "ObservationConfig": "config",
    "RewardConfig": "config",
    "WorldConfig": "config",
    "HorizonSync": "horizon",
    "ObservationLayout": "observation",
    "PRESETS": "presets",
    "PRIMITIVES": "actions",
    "REWARD_TERMS": "rewards",
}

__all__ = sorted(_HOMES)


def __getattr__(name: str):
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_HOMES[name]}", __name__), name)
    globals()[name] = value
    return value
