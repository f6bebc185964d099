"""The team env's configuration: the single-robot env's sections (``EnvConfig``) plus a ``team`` section.

``TeamEnvConfig`` is an ``EnvConfig`` (the same ``world``, ``robot``, ``sensor``, ``odometry``, ``filter``,
``reward``, ``observation`` and ``action`` sections, validated by the same code) with a ``team`` section and
defaults for a team: motion primitives held 10 control steps, 50 env steps (500 control steps of 0.1 s, as
EKFSLAM-v0). Built from keyword overrides or a YAML file of sections (``build_team_config``); an unknown or bad
value raises ``ValueError`` naming the field, e.g. ``team.n_robots``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..envs.config import ActionConfig, EnvConfig

MAX_ROBOTS = 5  # MRCLAM's team size; the observation's teammate slots default to MAX_ROBOTS - 1


@dataclass(frozen=True)
class TeamConfig:
    """The team.

    n_robots: robots in the team, 1 to ``MAX_ROBOTS``; robot 0 starts at the layout's start pose, the others
    around it. start_spacing: m between neighbouring robots at the start (they stand in a row across robot 0's
    heading, or wherever the walls leave room within ``start_spread`` m). robot_readings: whether robots read
    each other's positions (range, bearing and identity, with the landmark sensor's noise, range and field of
    view) and the filter fuses them; off, the robots share only the map. teammate_slots: teammates in each
    robot's observation, nearest first (more than n_robots - 1 leaves slots empty, so one policy serves teams of
    several sizes).
    """

    n_robots: int = 3
    start_spacing: float = 1.0
    start_spread: float = 4.0
    robot_readings: bool = True
    teammate_slots: int = MAX_ROBOTS - 1

    def __post_init__(self) -> None:
        ok = isinstance(self.n_robots, int) and not isinstance(self.n_robots, bool)
        if not (ok and 1 <= self.n_robots <= MAX_ROBOTS):
            raise ValueError(f"team.n_robots must be an integer in [1, {MAX_ROBOTS}], got {self.n_robots!r}")
        for name in ("start_spacing", "start_spread"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"team.{name} must be > 0, got {value!r}")
        if not isinstance(self.robot_readings, bool):
            raise ValueError(f"team.robot_readings must be true or false, got {self.robot_readings!r}")
        ok = isinstance(self.teammate_slots, int) and not isinstance(self.teammate_slots, bool)
        if not (ok and self.teammate_slots >= 0):
            raise ValueError(f"team.teammate_slots must be an integer >= 0, got {self.teammate_slots!r}")


def _team_action() -> ActionConfig:
    return ActionConfig(kind="primitives")


@dataclass(frozen=True)
class TeamEnvConfig(EnvConfig):
    """``EnvConfig`` with a ``team`` section; ``action`` defaults to motion primitives (the only kind a team
    takes: one Discrete action per robot) and the episode to 50 env steps of 10 control steps."""

    action: ActionConfig = field(default_factory=_team_action)
    max_episode_steps: int = 50
    team: TeamConfig = field(default_factory=TeamConfig)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.action.kind != "primitives":
            raise ValueError(
                f"action.kind must be primitives in a team env (one Discrete action per robot), got "
                f"{self.action.kind!r}"
            )
        if self.filter.association != "known":
            raise ValueError(
                f"filter.association must be known in a team env, got {self.filter.association!r}"
            )
        if self.sensor.clutter_rate > 0:
            raise ValueError(f"sensor.clutter_rate must be 0 in a team env, got {self.sensor.clutter_rate!r}")
        if self.observation.kind != "box" or self.observation.belief_image or self.observation.last_action:
            raise ValueError(
                "observation.kind must be box, without belief_image or last_action, in a team env, got "
                f"kind={self.observation.kind!r}, belief_image={self.observation.belief_image}, "
                f"last_action={self.observation.last_action}"
            )


def build_team_config(
    config: TeamEnvConfig | str | Path | Mapping[str, Any] | None = None,
    n_robots: int | None = None,
    **overrides: Any,
) -> TeamEnvConfig:
    """The team env's configuration: a complete ``TeamEnvConfig``, a mapping of sections or a YAML file of them
    (onto the defaults), then ``overrides`` (sections) on top, then ``n_robots`` (``team.n_robots``) if given."""
    if isinstance(config, TeamEnvConfig):
        built = TeamEnvConfig.from_overrides(config, **overrides)
    elif isinstance(config, (str, Path)):
        built = TeamEnvConfig.from_yaml(config, **overrides)
    elif isinstance(config, Mapping):
        built = TeamEnvConfig.from_overrides(TeamEnvConfig.from_overrides(**config), **overrides)
    elif config is None:
        built = TeamEnvConfig.from_overrides(**overrides)
    else:
        raise TypeError(
            f"config must be a TeamEnvConfig, a YAML path or a mapping, got {type(config).__name__}"
        )
    if n_robots is not None:
        built = TeamEnvConfig.from_overrides(built, team={"n_robots": n_robots})
    return built
