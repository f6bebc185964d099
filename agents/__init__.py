"""Agents for the EKFSLAM envs behind one interface: ``reset(env, seed)`` then ``act(observation) -> action``.

Baselines: ``random`` (uniform actions), ``circle`` (a fixed circle, a sanity floor), ``lawnmower`` (a
coverage sweep of the world's bounds), ``greedy`` (D-optimal information gain over motion primitives, the
classic active-SLAM baseline; ``greedy2`` is the same planner looking two primitives ahead), ``frontier``
(nearest-frontier exploration, Yamauchi 1997, the exploration literature's baseline), and ``ppo`` (a saved
stable-baselines3 policy; needs the ``train`` extra).
``make_agent(name, **kwargs)`` builds one by name, as ``python -m ekfslam_gym.evaluate --agent NAME`` does.
The planners that demonstrate in a macro action interface, for behaviour cloning, are in ``planners``;
``extractors`` holds ``BeliefCNN``, the features extractor configs name by its dotted path. Training itself is
``ekfslam_gym.training``.
"""

from __future__ import annotations

from typing import Any

from .base import Agent, clip_action, wall_scan
from .baselines import CircleAgent, LawnmowerAgent, RandomAgent
from .frontier import FrontierAgent
from .greedy import GreedyInfoGainAgent, GreedyLookaheadAgent
from .ppo import PPOAgent

AGENTS: dict[str, type[Agent]] = {
    "random": RandomAgent,
    "circle": CircleAgent,
    "lawnmower": LawnmowerAgent,
    "greedy": GreedyInfoGainAgent,
    "greedy2": GreedyLookaheadAgent,
    "frontier": FrontierAgent,
    "ppo": PPOAgent,
}
BASELINES: tuple[str, ...] = ("random", "circle", "lawnmower", "greedy", "frontier")


def make_agent(name: str, **kwargs: Any) -> Agent:
    """The agent registered as ``name`` built with ``kwargs`` (e.g. ``make_agent("ppo", model_path=...)``)."""
    try:
        cls = AGENTS[name]
    except KeyError:
        raise ValueError(f"unknown agent {name!r}; choose one of {sorted(AGENTS)}") from None
    return cls(**kwargs)


__all__ = [
    "AGENTS",
    "BASELINES",
    "Agent",
    "CircleAgent",
    "FrontierAgent",
    "GreedyInfoGainAgent",
    "GreedyLookaheadAgent",
    "LawnmowerAgent",
    "PPOAgent",
    "RandomAgent",
    "clip_action",
    "make_agent",
    "wall_scan",
]
