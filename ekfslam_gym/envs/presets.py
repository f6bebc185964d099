"""The registered configurations, as config overrides (``configs/env/*.yaml`` hold the same, for reading)."""

from __future__ import annotations

PRESETS: dict[str, dict] = {
    "EKFSLAM-v0": {},
    "EKFSLAM-Loop-v0": {"world": {"layout": "loop"}, "max_episode_steps": 800},
    "EKFSLAM-Large-v0": {
        "world": {"layout": "rooms", "n_landmarks": 120, "layout_kwargs": {"width": 40.0, "height": 40.0}},
        "max_episode_steps": 1000,
    },
}
