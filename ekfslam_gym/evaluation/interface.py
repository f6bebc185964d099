"""The one check every loop that steps an env for an agent makes: that the agent acts in the env's interface.

A velocity command and a waypoint goal are both two floats in [-1, 1], so the env cannot tell one from the
other: without this check a velocity agent in a waypoint env runs without a word and its episode scores some
other agent. Nothing here imports the agents: an agent declares its interface as ``action_kind``.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym


def check_action_kind(agent: Any, env: gym.Env) -> None:
    """ValueError when ``agent`` declares an action interface (``action_kind``, as ``ekfslam_gym.agents.Agent``
    does) other than the env's ``action.kind``. An agent that declares nothing (None, or no attribute: a user's
    own) is taken at its word."""
    declared = getattr(agent, "action_kind", None)
    kind = env.unwrapped.config.action.kind
    if declared is not None and str(declared) != kind:
        name = getattr(agent, "name", type(agent).__name__)
        raise ValueError(
            f"agent {name!r} acts in action.kind {str(declared)!r} and this env takes {kind!r} actions; run it in "
            f"an env of action.kind {str(declared)!r}, or give an agent that acts in {kind!r}"
        )
