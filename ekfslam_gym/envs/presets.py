"""The registered configurations, as config overrides (``configs/env/*.yaml`` hold the v0 ones, for reading),
and each id's one-line description and version history (``DESCRIPTIONS``, ``VERSION_HISTORY``: what the docs'
env pages and the versioning page are made from).

A v1 id is ``V1`` (what changed from v0, for every v1 id) plus its world and its episode length in simulated
time. The family ids (``EKFSLAM-<Family>-v1``) take a ``tier`` keyword (``preset_overrides``); their horizon is
the tier's ``TIER_EPISODE_TIME``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

V1: dict[str, Any] = {
    "filter": {"initial_draw": True},
    "terminate_on_complete": False,
    "max_episode_steps": None,
}
"""What every v1 id changes from v0: the filter's initial pose drawn from its prior, no end on a complete map
(a fixed horizon: the return telescopes to the drop in log det Sigma, so completing the map sooner never earns
less), and the episode's length in simulated time (``episode_time``, ``ekfslam_gym.envs.episode``)."""

LARGE_WORLD: dict[str, Any] = {
    "layout": "rooms",
    "n_landmarks": 120,
    "layout_kwargs": {"width": 40.0, "height": 40.0},
}

TIERS: tuple[str, ...] = ("easy", "medium", "hard")
DEFAULT_TIER = "medium"
TIER_EPISODE_TIME: dict[str, float] = {"easy": 60.0, "medium": 120.0, "hard": 240.0}
"""s of simulated time per tier of a family id."""

PRESETS: dict[str, dict] = {
    "EKFSLAM-v0": {},
    "EKFSLAM-Loop-v0": {"world": {"layout": "loop"}, "max_episode_steps": 800},
    "EKFSLAM-Large-v0": {"world": LARGE_WORLD, "max_episode_steps": 1000},
    "EKFSLAM-v1": {**V1, "episode_time": 50.0},
    "EKFSLAM-Loop-v1": {**V1, "world": {"layout": "loop"}, "episode_time": 80.0},
    "EKFSLAM-Large-v1": {**V1, "world": LARGE_WORLD, "episode_time": 600.0},
}

FAMILY_IDS: dict[str, str] = {}
"""The family ids (``EKFSLAM-<Family>-v1``) by id: their layout family, whose tiers ``tier=`` picks."""


@dataclass(frozen=True)
class Release:
    """One row of an id's version history: the id's version, the package release that brought it, and what
    changed."""

    version: str
    package: str
    changes: str


_V0 = Release("v0", "0.2.0", "first version under the env-version policy (the behaviour of release 0.2.0)")
_V1 = Release(
    "v1",
    "0.3.0",
    "a fixed horizon in simulated time, the same for every action kind (no end on a complete map; "
    "``info['time_to_complete']`` says when it was); the filter's initial pose drawn from its prior "
    "(``filter.initial_draw``)",
)
_V1_NEW = Release("v1", "0.3.0", "new in v1: a fixed horizon in simulated time, the filter's initial draw on")

DESCRIPTIONS: dict[str, str] = {
    "EKFSLAM-v0": "20 x 20 m arena, 30 landmarks, 500 steps of 0.1 s.",
    "EKFSLAM-Loop-v0": "a corridor ring (the loop layout), 30 landmarks, 800 steps: closing the loop pays.",
    "EKFSLAM-Large-v0": "40 x 40 m rooms, 120 landmarks, 1000 steps.",
    "EKFSLAM-v1": "20 x 20 m arena, 30 landmarks, 50 s.",
    "EKFSLAM-Loop-v1": "a corridor ring, 30 landmarks, 80 s.",
    "EKFSLAM-Large-v1": "40 x 40 m rooms, 120 landmarks, 600 s: long enough for the frontier planner to see "
    "at least 90 % of the landmarks.",
}
"""One line per id: what its world and horizon are."""

VERSION_HISTORY: dict[str, tuple[Release, ...]] = {
    "EKFSLAM": (_V0, _V1),
    "EKFSLAM-Loop": (_V0, _V1),
    "EKFSLAM-Large": (
        _V0,
        Release("v1", "0.3.0", f"{_V1.changes}; 600 s instead of 100 s, so the map can be completed"),
    ),
}
"""Each id's versions, by the id without its version suffix, oldest first."""


def id_base(env_id: str) -> str:
    """``EKFSLAM-Loop-v1`` -> ``EKFSLAM-Loop``: the key of ``VERSION_HISTORY``."""
    base, _, version = env_id.rpartition("-v")
    if not base or not version.isdigit():
        raise ValueError(f"{env_id!r} is no versioned env id (NAME-vN)")
    return base


def preset_overrides(preset: str, tier: str | None = None) -> Mapping[str, Any]:
    """The overrides of the registered id ``preset``; ``tier`` (family ids only) picks the family's tier: its
    world and its horizon. ValueError naming the choices for an unknown preset or tier."""
    if preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; known: {sorted(PRESETS)} or None (the defaults)")
    if tier is None:
        return PRESETS[preset]
    if preset not in FAMILY_IDS:
        raise ValueError(
            f"tier= applies to the family ids ({', '.join(FAMILY_IDS) or 'none yet'}), not {preset}"
        )
    if tier not in TIERS:
        raise ValueError(f"tier must be one of {'|'.join(TIERS)}, got {tier!r}")
    return family_preset(FAMILY_IDS[preset], tier)


def family_preset(family: str, tier: str) -> dict[str, Any]:
    """The v1 overrides of ``family`` at ``tier``: its world section and the tier's horizon."""
    from ..sim.families import world_section

    return {**V1, "world": world_section(family, tier), "episode_time": TIER_EPISODE_TIME[tier]}


MIX_ID = "EKFSLAM-Mix-v1"
"""The id that draws a training family and a tier at every reset (``ekfslam_gym.envs.mixed``)."""


def registered_entry_point(env_id: str) -> str:
    """The class ``gym.make(env_id)`` builds."""
    if env_id == MIX_ID:
        return "ekfslam_gym.envs.mixed:MixedFamiliesEnv"
    return "ekfslam_gym.envs.ekfslam_env:EKFSLAMEnv"
