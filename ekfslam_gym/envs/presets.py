"""The registered configurations, as config overrides (``configs/env/*.yaml`` hold the v0 ones, for reading),
and each id's one-line description and version history (``DESCRIPTIONS``, ``VERSION_HISTORY``: what the docs'
env pages and the versioning page are made from).

A v1 id is ``V1`` (what every v1 id changes from v0) plus its world and its episode length in simulated time.
There is a v1 id per layout family (``ekfslam_gym.sim.families``): ``EKFSLAM-v1`` is the ``arena`` family,
``EKFSLAM-Loop-v1`` the ``loop`` family, and every other family is ``EKFSLAM-<Family>-v1`` (``figure_eight``:
``EKFSLAM-FigureEight-v1``). A family id takes ``tier="easy" | "medium" | "hard"`` (``DEFAULT_TIER`` when left
out; the medium tiers of arena and loop are the v0 worlds), whose world is the family's at that tier and whose
horizon is the tier's ``TIER_EPISODE_TIME``. ``EKFSLAM-Large-v1`` keeps the 40 x 40 m rooms of Large-v0 with a
horizon long enough to complete them, and ``EKFSLAM-Mix-v1`` draws a training family and a tier at every reset
(``ekfslam_gym.envs.mixed``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..seeds import TRAINING_FAMILIES
from ..sim.families import FAMILIES, TIERS, world_section

V1: dict[str, Any] = {
    "filter": {"initial_draw": True},
    "terminate_on_complete": False,
    "max_episode_steps": None,
}
"""What every v1 id changes from v0: the filter's initial pose drawn from its prior, no end on a complete map
(a fixed horizon: the return telescopes to the drop in log det Sigma, so completing the map sooner never earns
less), and the episode's length in simulated time (``episode_time``, ``ekfslam_gym.envs.episode``)."""

DEFAULT_TIER = "medium"
TIER_EPISODE_TIME: dict[str, float] = {"easy": 90.0, "medium": 150.0, "hard": 330.0}
"""s of simulated time per tier of a family id: 1.5 times the longest time the frontier planner took to see
90 % of the landmarks of a training family at that tier (the median of three evaluation seeds; office left out,
where it stalls below 90 % whatever the time), rounded up to 30 s (docs/versioning.md has the figures)."""

LARGE_WORLD: dict[str, Any] = {
    "layout": "rooms",
    "n_landmarks": 120,
    "layout_kwargs": {"width": 40.0, "height": 40.0},
}
MIX_ID = "EKFSLAM-Mix-v1"
"""The id that draws a training family and a tier at every reset (``ekfslam_gym.envs.mixed``)."""


def family_id(family: str) -> str:
    """The v1 id of a layout family: ``EKFSLAM-v1`` (arena), ``EKFSLAM-Loop-v1``, ``EKFSLAM-<Family>-v1``."""
    special = {"arena": "EKFSLAM-v1", "loop": "EKFSLAM-Loop-v1"}
    return special.get(family, "EKFSLAM-" + "".join(part.title() for part in family.split("_")) + "-v1")


def family_preset(family: str, tier: str = DEFAULT_TIER) -> dict[str, Any]:
    """The v1 overrides of ``family`` at ``tier``: its world section and the tier's horizon."""
    return {**V1, "world": world_section(family, tier), "episode_time": TIER_EPISODE_TIME[tier]}


FAMILY_IDS: dict[str, str] = {family_id(family): family for family in FAMILIES}
"""The family ids by id: their layout family, whose tiers ``tier=`` picks."""

GENERALIST_IDS: tuple[str, ...] = (*FAMILY_IDS, "EKFSLAM-Large-v1")
"""The v1 layout ids a policy trained on ``EKFSLAM-Mix-v1`` is made for: every family id (training and held-out
families alike, at any tier) and Large-v1. They share Mix-v1's spaces, so one such policy (the shipped
generalist) serves them all."""


def trained_for(env_id: str) -> tuple[str, ...]:
    """The ids a policy trained on ``env_id`` is meant to run on: its own, and for ``EKFSLAM-Mix-v1`` also every
    ``GENERALIST_IDS`` id (``env_id`` may carry a ``module:`` prefix)."""
    env_id = env_id.split(":")[-1]
    return (env_id, *GENERALIST_IDS) if env_id == MIX_ID else (env_id,)


PRESETS: dict[str, dict] = {
    "EKFSLAM-v0": {},
    "EKFSLAM-Loop-v0": {"world": {"layout": "loop"}, "max_episode_steps": 800},
    "EKFSLAM-Large-v0": {"world": LARGE_WORLD, "max_episode_steps": 1000},
    **{env_id: family_preset(family) for env_id, family in FAMILY_IDS.items()},
    "EKFSLAM-Large-v1": {**V1, "world": LARGE_WORLD, "episode_time": 600.0},
    # The world here is the first training family's; MixedFamiliesEnv draws another at every reset.
    MIX_ID: family_preset(TRAINING_FAMILIES[0]),
}


@dataclass(frozen=True)
class Release:
    """One row of an id's version history: the id's version, the package release that brought it, and what
    changed."""

    version: str
    package: str
    changes: str


_V0 = Release("v0", "0.2.0", "first version under the env-version policy (the behaviour of release 0.2.0)")
_V1_CHANGES = (
    "a fixed horizon in simulated time, the same for every action kind, set by the tier (no end on a complete "
    "map: ``info['time_to_complete']`` says when it was); the filter's initial pose drawn from its prior "
    "(``filter.initial_draw``); ``tier=`` picks the family's easy, medium or hard world"
)
_V1_NEW = Release("v1", "0.3.0", f"new, with every v1 id: {_V1_CHANGES}")

_FAMILY_LINES = {
    "arena": "an open rectangle",
    "pillars": "an open hall with pillars that hide the landmarks behind them",
    "rooms": "a grid of rooms joined by doorways",
    "loop": "a corridor ring round a closed block: closing the loop pays",
    "figure_eight": "two corridor rings sharing a middle corridor",
    "office": "rooms off a corridor spine",
    "warehouse": "aisles between rows of shelves (a held-out family)",
    "maze": "corridors that branch and end in dead ends (a held-out family)",
}

DESCRIPTIONS: dict[str, str] = {
    "EKFSLAM-v0": "20 x 20 m arena, 30 landmarks, 500 steps of 0.1 s.",
    "EKFSLAM-Loop-v0": "A corridor ring (the loop layout), 30 landmarks, 800 steps: closing the loop pays.",
    "EKFSLAM-Large-v0": "40 x 40 m rooms, 120 landmarks, 1000 steps.",
    **{
        env_id: f"The {family} family, {_FAMILY_LINES[family]}; tier easy, medium (default) or hard, "
        f"{', '.join(f'{TIER_EPISODE_TIME[t]:g}' for t in TIERS)} s."
        for env_id, family in FAMILY_IDS.items()
    },
    "EKFSLAM-Large-v1": "40 x 40 m rooms, 120 landmarks, 600 s: long enough for the frontier planner to see "
    "at least 90 % of the landmarks.",
    MIX_ID: "A training family and a tier drawn at every reset, for training policies that generalise; the "
    "tier's horizon.",
}
"""One line per id: what its world and horizon are."""

VERSION_HISTORY: dict[str, tuple[Release, ...]] = {
    **{
        family_id(f).rpartition("-v")[0]: (
            _V0,
            Release("v1", "0.3.0", f"the {f} family, whose medium tier is the v0 world: {_V1_CHANGES}"),
        )
        for f in ("arena", "loop")
    },
    "EKFSLAM-Large": (
        _V0,
        Release(
            "v1",
            "0.3.0",
            "a fixed horizon in simulated time (no end on a complete map), the filter's initial draw; 600 s "
            "instead of 100 s, so that the map can be completed",
        ),
    ),
    **{family_id(f).rpartition("-v")[0]: (_V1_NEW,) for f in FAMILIES if f not in ("arena", "loop")},
    MIX_ID.rpartition("-v")[0]: (_V1_NEW,),
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
        raise ValueError(f"tier= applies to the family ids ({', '.join(FAMILY_IDS)}), not {preset}")
    if tier not in TIERS:
        raise ValueError(f"tier must be one of {'|'.join(TIERS)}, got {tier!r}")
    return family_preset(FAMILY_IDS[preset], tier)


def registered_entry_point(env_id: str) -> str:
    """The class ``gym.make(env_id)`` builds."""
    if env_id == MIX_ID:
        return "ekfslam_gym.envs.mixed:MixedFamiliesEnv"
    return "ekfslam_gym.envs.ekfslam_env:EKFSLAMEnv"
