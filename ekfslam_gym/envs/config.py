"""One frozen, validated configuration per env, built at construction and never mutated (only
``EKFSLAMEnv.set_max_episode_steps`` replaces it, by a copy with another step limit).

Sections: ``world`` (layout and landmarks), ``robot``, ``sensor`` and ``odometry`` (the simulator's own
parameter classes), ``filter`` (``FilterConfig``: the filter's and the association's settings), ``reward``, ``observation``,
``action``, and the episode settings at the top level. Build one from keyword overrides
(``EnvConfig.from_overrides(world={"n_landmarks": 50})``) or a YAML file under ``configs/env/``
(``EnvConfig.from_yaml(path)``); an unknown or invalid value raises ``ValueError`` naming the field, e.g.
``sensor.max_range``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..filter.settings import ASSOCIATION_NAMES, AssociationSettings, FilterSettings, check_association
from ..sim.odometry import OdometryNoise
from ..sim.robot import RobotParams
from ..sim.sensor import SensorParams
from .presets import PRESETS
from .rewards import REWARD_TERMS


def _require(condition: bool, name: str, message: str, value: Any) -> None:
    if not condition:
        raise ValueError(f"{name} {message}, got {value!r}")


def _positive(name: str, value: Any) -> None:
    _require(
        isinstance(value, (int, float)) and math.isfinite(value) and value > 0, name, "must be > 0", value
    )


def _non_negative(name: str, value: Any) -> None:
    _require(
        isinstance(value, (int, float)) and math.isfinite(value) and value >= 0, name, "must be >= 0", value
    )


def _integer(name: str, value: Any, minimum: int) -> None:
    ok = isinstance(value, int) and not isinstance(value, bool) and value >= minimum
    _require(ok, name, f"must be an integer >= {minimum}", value)


@dataclass(frozen=True)
class WorldConfig:
    """The layout generator (a name of ``ekfslam_gym.sim.LAYOUTS``: a layout family such as ``arena``, ``rooms``,
    ``loop`` or ``maze``, ``surveyed`` with the landmark positions given, or ``map_server`` for a ROS map), the
    exact number of landmarks, and keyword arguments passed to the generator (sizes in m, e.g.
    ``{"width": 20.0}``; each layout's keywords: ``ekfslam_gym.sim.layout_keywords``). A keyword the layout does
    not take, or a value of the wrong kind, raises here, naming ``world.layout_kwargs.<key>``; the env's config
    also draws the layout once (``check_world``), so a value the generator refuses raises when the config is
    built, not at the first reset."""

    layout: str = "arena"
    n_landmarks: int = 30
    layout_kwargs: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from ..sim.layouts import LAYOUTS, check_layout_kwargs

        _require(self.layout in LAYOUTS, "world.layout", f"must be one of {sorted(LAYOUTS)}", self.layout)
        _integer("world.n_landmarks", self.n_landmarks, 1)
        _require(
            isinstance(self.layout_kwargs, Mapping),
            "world.layout_kwargs",
            "must be a mapping",
            self.layout_kwargs,
        )
        object.__setattr__(self, "layout_kwargs", check_layout_kwargs(self.layout, self.layout_kwargs))


def check_world(world: WorldConfig, robot_radius: float) -> None:
    """Draw ``world``'s layout once (seed 0, for a robot of ``robot_radius`` m, as the env's reset does), so that
    a value its generator refuses (a size too small, a map file that is missing or malformed, more landmarks
    than fit) raises ValueError when the config is built. Each distinct world is drawn once per process."""
    key = (world.layout, world.n_landmarks, _frozen(world.layout_kwargs), float(robot_radius))
    if key in _checked_worlds:
        return
    import numpy as np

    from ..sim.layouts import make_layout

    try:
        kwargs = {"robot_radius": float(robot_radius), **world.layout_kwargs}
        make_layout(world.layout, np.random.default_rng(0), world.n_landmarks, **kwargs)
    except ValueError as error:
        raise ValueError(f"world (layout {world.layout!r}): {error}") from None
    if len(_checked_worlds) >= 256:
        _checked_worlds.clear()
    _checked_worlds.add(key)


_checked_worlds: set[tuple] = set()


def _frozen(value: Any) -> Any:
    """A hashable copy of a layout_kwargs value (mappings, sequences and arrays nested in any way)."""
    if isinstance(value, Mapping):
        return tuple(sorted((str(k), _frozen(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple)):
        return tuple(_frozen(v) for v in value)
    if hasattr(value, "tobytes") and hasattr(value, "shape"):
        return (str(value.dtype), value.shape, value.tobytes())
    return value


@dataclass(frozen=True)
class FilterConfig(FilterSettings):
    """The env's ``filter`` section, one flat mapping for the user: the filter's own settings (the fields of
    ``FilterSettings``, its defaults), how readings find their landmarks (``association``, ``gate_prob``,
    ``new_gate_prob``, ``confirm_steps``: ``AssociationSettings``' fields and defaults, ``association`` its
    ``kind``) and how the env starts the estimate (``initial_draw``). The env hands ``settings`` to
    ``EKFSLAM`` and ``association_settings`` to ``EKFSLAM.correct_unknown``.

    initial_draw: the env starts the filter's pose estimate at a draw from its own prior, N(start, pose_prior I),
    instead of at the true start (``ekfslam_gym.envs.ekfslam_env.initial_estimate``; the world is unchanged).
    Started at the truth, the filter counts the prior's variance with no error to match it, so the first steps'
    pose NEES reads low (2.4 of 3 at step 0; ``docs/filter.md``). Pick it for consistency studies of the first
    steps; it is off in the v0 ids so that their recorded results stay.
    """

    association: str = AssociationSettings.kind
    gate_prob: float = AssociationSettings.gate_prob
    new_gate_prob: float = AssociationSettings.new_gate_prob
    confirm_steps: int = AssociationSettings.confirm_steps
    initial_draw: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        names = {name: f"filter.{name}" for name in ASSOCIATION_NAMES} | {"kind": "filter.association"}
        check_association(self.association, self.gate_prob, self.new_gate_prob, self.confirm_steps, names)
        _require(isinstance(self.initial_draw, bool), "filter.initial_draw", "must be true or false", self.initial_draw)  # fmt: skip
        filter_fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(FilterSettings)}
        object.__setattr__(self, "_settings", FilterSettings(**filter_fields))
        association = AssociationSettings(
            self.association, self.gate_prob, self.new_gate_prob, self.confirm_steps
        )
        object.__setattr__(self, "_association_settings", association)

    @property
    def settings(self) -> FilterSettings:
        """The filter's settings alone (what ``EKFSLAM`` takes)."""
        return self._settings

    @property
    def association_settings(self) -> AssociationSettings:
        """The association's settings alone (what ``EKFSLAM.correct_unknown`` takes)."""
        return self._association_settings


@dataclass(frozen=True)
class RewardConfig:
    """Weights of the reward terms (``ekfslam_gym.envs.rewards.REWARD_TERMS`` says what each term is). The
    reward is the sum of the terms times their weights; ``info["reward_terms"]`` reports every term unweighted,
    whatever its weight. The fields are REWARD_TERMS' names and defaults, in its order (a test holds them so)."""

    info_gain: float = 1.0  # per nat of log det Sigma dropped
    collision: float = 1.0  # per control step in contact with a wall
    step_cost: float = 0.0  # per control step
    coverage: float = 0.0  # per m^2 looked at for the first time
    pose_variance: float = 0.0  # per m^2 of the pose estimate's position variance, each control step

    def __post_init__(self) -> None:
        for term in REWARD_TERMS:
            value = getattr(self, term.name)
            _require(isinstance(value, (int, float)) and math.isfinite(value), f"reward.{term.name}", "must be finite", value)  # fmt: skip


@dataclass(frozen=True)
class ObservationConfig:
    """What the observation holds. kind: ``box`` (one flat float32 vector) or ``dict`` (named parts).

    k_nearest: landmark slots, the seen landmarks nearest the pose estimate, nearest first.
    grid, grid_extent: the coverage part is a grid x grid window centred on the pose estimate and turned with
    its heading, reaching grid_extent m to each side, read from a coverage memory of the world kept at
    memory_resolution m per cell (where the sensor has already looked). An MLP reads "unexplored, ahead on the
    left" from a robot-centred window far more easily than from a world-fixed map plus the pose.
    coarse_grid, coarse_extent: a second, coarser and wider window of the same memory (each cell the fraction
    looked at), so the far side of the world is not out of sight; coarse_grid 0 disables it.
    belief_image (``dict`` only, off by default): the Dict observation gains ``belief_image``, a float32
    (3, belief_size, belief_size) image in [0, 1] reaching belief_extent m to each side, centred on the pose
    estimate and turned with its heading like the coverage window, read from the belief alone: channel 0 the
    coverage memory, 1 the seen landmarks' estimates (each in its cell, weighted by its certainty
    1 / (1 + sqrt(tr Sigma_jj) / cell size)), 2 a memory of where the wall scan has hit a wall (placed at the
    pose estimate). For a CNN (``ekfslam_gym.agents.extractors.BeliefCNN``); ``ekfslam_gym.envs.observation`` has details.
    last_action (``dict`` only, off by default): the Dict observation gains ``last_action``, the action the
    last env step executed (zeros after reset): a float32 one-hot of the primitive in a primitives env, the
    clipped action (velocity or waypoint goal) otherwise. A policy's own commitment (a planner it imitates
    keeps driving the primitive it chose) is otherwise invisible to a feed-forward policy.
    """

    kind: str = "box"
    k_nearest: int = 8
    grid: int = 9
    grid_extent: float = 9.0
    memory_resolution: float = 0.5
    coarse_grid: int = 5
    coarse_extent: float = 20.0
    belief_image: bool = False
    belief_size: int = 16
    belief_extent: float = 8.0
    last_action: bool = False

    def __post_init__(self) -> None:
        _require(self.kind in ("box", "dict"), "observation.kind", "must be box|dict", self.kind)
        _integer("observation.k_nearest", self.k_nearest, 1)
        _integer("observation.grid", self.grid, 1)
        _positive("observation.grid_extent", self.grid_extent)
        _positive("observation.memory_resolution", self.memory_resolution)
        _integer("observation.coarse_grid", self.coarse_grid, 0)
        _positive("observation.coarse_extent", self.coarse_extent)
        _require(isinstance(self.belief_image, bool), "observation.belief_image", "must be a bool", self.belief_image)  # fmt: skip
        _require(
            not self.belief_image or self.kind == "dict",
            "observation.belief_image",
            f"needs observation.kind dict (a (C, H, W) image has no place in a flat box), kind is {self.kind!r}:"
            " must be false",
            self.belief_image,
        )
        _integer("observation.belief_size", self.belief_size, 2)
        _positive("observation.belief_extent", self.belief_extent)
        _require(isinstance(self.last_action, bool), "observation.last_action", "must be a bool", self.last_action)  # fmt: skip
        _require(
            not self.last_action or self.kind == "dict",
            "observation.last_action",
            f"needs observation.kind dict, kind is {self.kind!r}: must be false",
            self.last_action,
        )


ACTION_KINDS = ("velocity", "primitives", "waypoint")
DEFAULT_HOLD = {"velocity": 1, "primitives": 10, "waypoint": 10}


@dataclass(frozen=True)
class ActionConfig:
    """What one env step means (``ekfslam_gym.envs.actions`` describes each kind).

    kind: ``velocity`` (the (forward, turn) command), ``primitives`` (one of the greedy planner's motion
    primitives, ``Discrete``) or ``waypoint`` (a goal relative to the estimated pose, driven by a scan-only
    controller). hold: control steps per env step, at most for a waypoint; left out (None), the kind's default
    (``DEFAULT_HOLD``: 1 for velocity, 10 for the others), which the built config holds, so ``hold`` always
    reports the effective number; a change of ``kind`` without a ``hold`` takes the new kind's default.
    waypoint_radius: m, the reach of a waypoint goal (the action's unit). guard: m, primitives only: a control
    step whose forward travel would bring the robot within this distance of a wall the scan shows ahead turns
    without driving forward, and one that finds the robot already that near backs off, so the robot stops
    short of walls instead of sliding along them, where every contact costs the wheel odometry a slip (0, the
    default, is off). Pick it to cut wall contacts: trained under a guard of 0.2 m the Large recipe touched
    walls a quarter as often, at a small cost in map accuracy (docs/results.md, *A guard that stops short of
    walls*).
    """

    kind: str = "velocity"
    hold: int | None = field(default=None, metadata={"default_follows": "kind"})
    waypoint_radius: float = 3.0
    guard: float = 0.0

    def __post_init__(self) -> None:
        _require(
            self.kind in ACTION_KINDS, "action.kind", f"must be one of {'|'.join(ACTION_KINDS)}", self.kind
        )
        if self.hold is None:
            object.__setattr__(self, "hold", DEFAULT_HOLD[self.kind])
        _integer("action.hold", self.hold, 1)
        _positive("action.waypoint_radius", self.waypoint_radius)
        _non_negative("action.guard", self.guard)
        _require(self.guard == 0 or self.kind == "primitives", "action.guard", "applies to action.kind primitives "
                 f"only (a waypoint's controller stops short of walls itself), not {self.kind!r}", self.guard)  # fmt: skip

    @property
    def steps(self) -> int:
        """Control steps per env step (at most, for a waypoint): ``hold``."""
        return self.hold


@dataclass(frozen=True)
class EnvConfig:
    """Everything an EKFSLAM env needs; see the section classes for units and meanings.

    dt: control period (s); substeps: physics steps per control step; max_episode_steps: the time limit in env
    steps (truncation, and the horizon of the observation's time-left term; ``gym.make`` keeps its TimeLimit
    equal to it, see ``ekfslam_gym.envs.horizon``); terminate_on_collision: end the episode
    at the first wall contact; done_std: end the episode when every landmark's marginal standard deviation
    (sqrt of the larger eigenvalue of its 2x2 covariance, m) is below this (0 disables); loop_gap: a re-observed
    landmark unseen for at least this many steps counts as a loop closure.
    """

    world: WorldConfig = field(default_factory=WorldConfig)
    robot: RobotParams = field(default_factory=RobotParams)
    sensor: SensorParams = field(default_factory=SensorParams)
    odometry: OdometryNoise = field(default_factory=OdometryNoise)
    filter: FilterConfig = field(default_factory=FilterConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)
    observation: ObservationConfig = field(default_factory=ObservationConfig)
    action: ActionConfig = field(default_factory=ActionConfig)
    dt: float = 0.1
    substeps: int = 2
    max_episode_steps: int = 500
    terminate_on_collision: bool = False
    done_std: float = 0.1
    loop_gap: int = 50

    def __post_init__(self) -> None:
        _positive("dt", self.dt)
        _integer("substeps", self.substeps, 1)
        _integer("max_episode_steps", self.max_episode_steps, 1)
        _require(isinstance(self.terminate_on_collision, bool), "terminate_on_collision", "must be a bool", self.terminate_on_collision)  # fmt: skip
        _non_negative("done_std", self.done_std)
        _integer("loop_gap", self.loop_gap, 1)
        # The env's reward needs log det Sigma finite from the start: the course's zero pose prior is no option.
        _positive("filter.pose_prior", self.filter.pose_prior)
        check_world(self.world, self.robot.radius)

    # ------------------------------------------------------------------ building
    @classmethod
    def from_overrides(cls, base: EnvConfig | None = None, **overrides: Any) -> EnvConfig:
        """``base`` (default: the defaults) with nested overrides, e.g. ``sensor={"max_range": 4.0}``."""
        return _replace(base if base is not None else cls(), overrides, "")

    @classmethod
    def from_yaml(cls, path: str | Path, base: EnvConfig | None = None, **overrides: Any) -> EnvConfig:
        """Load a YAML file of (possibly partial) sections onto ``base`` (default: the defaults), then apply
        ``overrides`` on top."""
        import yaml

        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"env config {path} does not exist")
        data = yaml.safe_load(path.read_text()) or {}
        if not isinstance(data, Mapping):
            raise ValueError(f"{path}: the top level must be a mapping of config sections")
        try:
            config = cls.from_overrides(base, **data)
        except ValueError as error:
            raise ValueError(f"{path}: {error}") from None
        return cls.from_overrides(config, **overrides)

    def to_dict(self) -> dict[str, Any]:
        """A plain nested dict (YAML- and JSON-friendly) that ``from_overrides(**d)`` turns back into this."""
        return dataclasses.asdict(self)


def build_config(
    config: EnvConfig | str | Path | Mapping[str, Any] | None,
    preset: str | None,
    overrides: Mapping[str, Any],
) -> EnvConfig:
    """The env's configuration: a mapping of sections or a YAML file of them merged onto ``preset``'s (a
    registered id, ``ekfslam_gym.envs.presets``; None: the defaults), or a complete ``EnvConfig`` as it is;
    then ``overrides`` on top."""
    if preset is not None and preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; known: {sorted(PRESETS)} or None (the defaults)")
    if isinstance(config, EnvConfig):
        return EnvConfig.from_overrides(config, **overrides)
    base = EnvConfig.from_overrides(**PRESETS[preset]) if preset is not None else EnvConfig()
    if isinstance(config, (str, Path)):
        return EnvConfig.from_yaml(config, base, **overrides)
    if isinstance(config, Mapping):
        return EnvConfig.from_overrides(EnvConfig.from_overrides(base, **config), **overrides)
    if config is None:
        return EnvConfig.from_overrides(base, **overrides)
    raise TypeError(f"config must be an EnvConfig, a YAML path or a mapping, got {type(config).__name__}")


def _replace(obj: Any, overrides: Mapping[str, Any], prefix: str) -> Any:
    """dataclasses.replace, recursively, with errors that name the full field path."""
    if not isinstance(overrides, Mapping):
        raise ValueError(f"{prefix.rstrip('.') or 'config'} must be a mapping, got {overrides!r}")
    fields = {f.name: f for f in dataclasses.fields(obj)}
    changes: dict[str, Any] = {}
    for key, value in overrides.items():
        if key not in fields:
            raise ValueError(f"unknown config field {prefix}{key!s}; known: {sorted(fields)}")
        current = getattr(obj, key)
        if dataclasses.is_dataclass(current) and isinstance(value, Mapping):
            changes[key] = _replace(current, value, f"{prefix}{key}.")
        elif dataclasses.is_dataclass(current) and isinstance(value, type(current)):
            changes[key] = value
        elif dataclasses.is_dataclass(current):
            raise ValueError(f"{prefix}{key} must be a mapping of its fields, got {value!r}")
        else:
            changes[key] = _coerce(value, current, f"{prefix}{key}")
    for name, f in fields.items():
        # A field whose default depends on another (action.hold on action.kind) returns to its default when
        # that one changes and it is not given itself.
        leader = f.metadata.get("default_follows")
        if leader in changes and name not in changes and changes[leader] != getattr(obj, leader):
            changes[name] = f.default
    try:
        return dataclasses.replace(obj, **changes)
    except (ValueError, TypeError) as error:
        message = str(error)
        section = prefix.rstrip(".")
        if section and not message.startswith(section):
            message = f"{section}: {message}"
        raise ValueError(message) from None


def _coerce(value: Any, current: Any, name: str) -> Any:
    """Check a leaf against its default's type. YAML writes 5 for 5.0: ints are accepted where the default is a
    float, nothing looser (a string where a number belongs is an error naming the field)."""
    is_number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if isinstance(current, bool):
        if not isinstance(value, bool):
            raise ValueError(f"{name} must be true or false, got {value!r}")
    elif isinstance(current, float):
        if not is_number:
            raise ValueError(f"{name} must be a number, got {value!r}")
        return float(value)
    elif isinstance(current, int):
        if not (isinstance(value, int) and not isinstance(value, bool)):
            raise ValueError(f"{name} must be an integer, got {value!r}")
    elif isinstance(current, str) and not isinstance(value, str):
        raise ValueError(f"{name} must be a string, got {value!r}")
    return value
