"""Agents for the EKFSLAM envs behind one interface: ``reset(env, seed)`` then ``act(observation) -> action``.

Baselines: ``random`` (uniform actions), ``circle`` (a fixed circle, a sanity floor), ``lawnmower`` (a
coverage sweep of the world's bounds), ``greedy`` (D-optimal information gain over motion primitives, the
classic active-SLAM baseline; ``greedy2`` is the same planner looking two primitives ahead), ``frontier``
(nearest-frontier exploration, Yamauchi 1997, the exploration literature's baseline), and ``ppo`` (a saved
stable-baselines3 policy; needs the ``train`` extra). These act in the ``velocity`` interface (``ppo`` in the one
it was trained in); ``greedy-primitives``, ``frontier-primitives`` and ``frontier-waypoint`` are the planners that
demonstrate for behaviour cloning, acting in the interface their names end with.
``make_agent(name, **kwargs)`` builds one by name, as ``ekfslam-evaluate --agent NAME`` does; a
name of the form ``module:Class`` (or ``module:function``, a factory) builds a user's own agent, any object with
``reset(env, seed)`` and ``act(observation)`` (docs/writing-an-agent.md). What ``act`` returns is declared by
the agent's ``action_kind`` (``ActionKind``: velocity, waypoint or primitives, the env's ``action.kind``).
The planners that demonstrate in a macro action interface, for behaviour cloning, are in ``planners``;
``navigation`` holds the pieces the planners share (the grid, the wall memory, Dijkstra, frontiers, the wall
veto); ``extractors`` holds ``BeliefCNN``, the features extractor configs name by its dotted path. Training itself is
``ekfslam_gym.training``.
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import Any

from . import _name_guard  # noqa: F401  (first: refuses the name `agents`)
from .base import ActionKind, Agent, clip_action, wall_scan
from .baselines import CircleAgent, LawnmowerAgent, RandomAgent
from .frontier import FrontierAgent, FrontierPrimitivesPlanner, FrontierWaypointPlanner
from .greedy import GreedyInfoGainAgent, GreedyLookaheadAgent
from .planners import GreedyPrimitivesPlanner
from .ppo import PPOAgent

AGENTS: dict[str, type[Agent]] = {
    "random": RandomAgent,
    "circle": CircleAgent,
    "lawnmower": LawnmowerAgent,
    "greedy": GreedyInfoGainAgent,
    "greedy2": GreedyLookaheadAgent,
    "frontier": FrontierAgent,
    "ppo": PPOAgent,
    # The demonstration planners by their own names, each acting in the macro interface its name ends with: it
    # needs an env of that action.kind (``--env-kwargs '{"action": {"kind": "primitives"}}'``).
    "greedy-primitives": GreedyPrimitivesPlanner,
    "frontier-primitives": FrontierPrimitivesPlanner,
    "frontier-waypoint": FrontierWaypointPlanner,
}
BASELINES: tuple[str, ...] = ("random", "circle", "lawnmower", "greedy", "frontier")


def is_agent_name(name: str) -> bool:
    """Whether ``name`` names an agent ``make_agent`` can build: a registered one or a ``module:attribute``."""
    return name in AGENTS or is_import_path(name)


def is_import_path(name: str) -> bool:
    """Whether ``name`` has the ``module:attribute`` form of a user's own agent."""
    module, sep, attribute = name.partition(":")
    return bool(sep and module and attribute)


def make_agent(name: str, **kwargs: Any) -> Agent:
    """The agent registered as ``name`` built with ``kwargs`` (e.g. ``make_agent("ppo", model_path=...)``), or
    for ``module:attribute`` the class or factory function there called with ``kwargs`` (the module is looked
    for on the path, then in the current folder). ValueError for an unknown name or an object that lacks
    ``reset`` or ``act``."""
    if is_import_path(name):
        agent = _import_attribute(name)(**kwargs)
        missing = [m for m in ("reset", "act") if not callable(getattr(agent, m, None))]
        if missing:
            raise ValueError(f"{name} built {agent!r}, which has no {' or '.join(missing)} method (an agent needs "
                             "reset(env, seed) and act(observation))")  # fmt: skip
        return agent
    try:
        cls = AGENTS[name]
    except KeyError:
        raise ValueError(
            f"unknown agent {name!r}; choose one of {sorted(AGENTS)} or give module:Class"
        ) from None
    return cls(**kwargs)


def _import_attribute(name: str) -> Any:
    """The class or function ``module:attribute`` names (a console script does not put the current folder on
    the path, so it is tried last)."""
    module_name, _, attribute = name.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as error:
        if error.name != module_name.split(".")[0] or os.getcwd() in sys.path:
            raise ValueError(f"cannot import {module_name!r} for agent {name!r}: {error}") from None
        sys.path.append(os.getcwd())
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as again:
            raise ValueError(f"cannot import {module_name!r} for agent {name!r}: {again}") from None
    try:
        built = getattr(module, attribute)
    except AttributeError:
        raise ValueError(f"module {module_name!r} has no {attribute!r} (agent {name!r})") from None
    if not callable(built):
        raise ValueError(f"{name} is not a class or a function")
    return built


__all__ = [
    "AGENTS",
    "BASELINES",
    "ActionKind",
    "Agent",
    "CircleAgent",
    "FrontierAgent",
    "FrontierPrimitivesPlanner",
    "FrontierWaypointPlanner",
    "GreedyInfoGainAgent",
    "GreedyLookaheadAgent",
    "GreedyPrimitivesPlanner",
    "LawnmowerAgent",
    "PPOAgent",
    "RandomAgent",
    "clip_action",
    "is_agent_name",
    "make_agent",
    "wall_scan",
]
