"""EKFSLAM-Mix-v1: a training family and a tier drawn at every reset, for policies meant to generalise.

The observation and action spaces are fixed at construction and do not depend on the world: the observation
is normalised by the world's size, holds the k nearest landmarks whatever their number, and reads fixed-size
windows of the coverage memory. The filter, the coverage memory and the world are built anew at every reset,
sized to the drawn world, so nothing allocated once has to fit every family.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..sim.layouts import Layout
from .config import EnvConfig, WorldConfig
from .ekfslam_env import EKFSLAMEnv
from .episode import step_limit
from .presets import TIER_EPISODE_TIME, TIERS


class MixedFamiliesEnv(EKFSLAMEnv):
    """``EKFSLAMEnv`` whose world is drawn at every reset: a family of ``families`` (training families only,
    default all of them, ``ekfslam_gym.seeds.TRAINING_FAMILIES``) and a tier of ``tiers`` (default all three),
    uniformly, from the reset's seed; then the family's layout at that tier
    (``ekfslam_gym.sim.families.world_section``), for the tier's horizon (``TIER_EPISODE_TIME``) unless a step
    limit is given.

    The config's ``world`` section is not used (the draw replaces it); everything else is the config's.
    ``family`` and ``tier`` say what the last reset drew.
    """

    def __init__(
        self,
        config: EnvConfig | str | Path | Mapping[str, Any] | None = None,
        render_mode: str | None = None,
        *,
        preset: str | None = None,
        families: Sequence[str] | None = None,
        tiers: Sequence[str] = TIERS,
        **overrides: Any,
    ) -> None:
        from ..seeds import TRAINING_FAMILIES, check_training_family
        from ..sim.families import world_section

        super().__init__(config, render_mode, preset=preset, **overrides)
        families = tuple(TRAINING_FAMILIES if families is None else families)
        tiers = tuple(tiers)
        if not families or any(f not in TRAINING_FAMILIES for f in families):
            for family in families:
                check_training_family(family, "the mixed env's families")  # names a held-out family
            raise ValueError(
                f"families must be a non-empty list of {', '.join(TRAINING_FAMILIES)}, got {families!r}"
            )
        if not tiers or any(t not in TIERS for t in tiers):
            raise ValueError(f"tiers must be a non-empty list of {', '.join(TIERS)}, got {tiers!r}")
        self._draws = tuple((f, t) for f in families for t in tiers)
        self._worlds = {
            (f, t): EnvConfig.from_overrides(world=world_section(f, t)).world for f, t in self._draws
        }
        self._tier_steps = {
            t: step_limit(
                EnvConfig.from_overrides(
                    self.config, max_episode_steps=None, episode_time=TIER_EPISODE_TIME[t]
                )
            )
            for t in tiers
        }
        self.family: str | None = None
        self.tier: str | None = None

    def _make_layout(self, world: WorldConfig, rng: np.random.Generator) -> Layout:
        self.family, self.tier = self._draws[int(rng.integers(len(self._draws)))]
        if self.config.max_episode_steps is None:  # no step limit given: the tier's time
            self._max_steps = self._tier_steps[self.tier]
        return super()._make_layout(self._worlds[(self.family, self.tier)], rng)
