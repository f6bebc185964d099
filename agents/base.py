"""The agent interface every baseline, planner and the PPO agent share, and helpers for reading the observation.

An agent is reset with the env at the start of an episode (so a planner can hold on to the env's belief, its
config and the world's bounds) and then maps observations to actions. Nothing here steps the env: the
evaluator owns the loop, so every agent is scored by exactly the same code.

What an agent's ``act`` returns is declared, not guessed from the value: ``action_kind`` (an ``ActionKind``,
named as the env config's ``action.kind``) says which interface it acts in, and so the action's type; None
means the agent cannot tell (a saved policy on a Box action space whose record does not say), and the env's
own interface is taken (``ActionKind.of_env``).
"""

from __future__ import annotations

import math
from enum import Enum
from typing import Any

import gymnasium as gym
import numpy as np


class ActionKind(str, Enum):
    """The action interface an agent acts in, by the env config's ``action.kind``, and the type of its actions:

    - ``velocity``: a float32 array (2,) in [-1, 1], (forward speed / v_max, turn rate / omega_max), held one
      control step;
    - ``waypoint``: a float32 array (2,) in [-1, 1], a goal (forward, left) relative to the estimated pose in
      units of ``action.waypoint_radius``, driven to by the env's waypoint controller;
    - ``primitives``: an ``np.int64``, the index of a motion primitive (``ekfslam_gym.envs.actions.PRIMITIVES``).
    """

    VELOCITY = "velocity"
    WAYPOINT = "waypoint"
    PRIMITIVES = "primitives"

    def __str__(self) -> str:
        return self.value

    @classmethod
    def of_env(cls, env: gym.Env) -> ActionKind:
        """The interface ``env`` (any wrapper of an EKFSLAM env) takes its actions in."""
        return cls(env.unwrapped.config.action.kind)

    def action(self, value: Any) -> Any:
        """``value`` as an action of this kind: ``np.int64`` for a primitive's index, else a float32 array (2,)."""
        if self is ActionKind.PRIMITIVES:
            return np.int64(np.asarray(value).reshape(()))
        return np.asarray(value, dtype=np.float32).reshape(2)


class Agent:
    """Base class: ``reset(env, seed)`` once per episode, then ``act(observation) -> action``.

    ``act`` returns an action of the agent's ``action_kind`` (``ActionKind``): by default a float32 array of
    shape (2,) in [-1, 1], (forward speed / v_max, turn rate / omega_max). Subclasses that need the belief read
    ``self.env`` (the unwrapped ``EKFSLAMEnv``: ``filter``, ``config``); they must not step it.
    """

    name: str = "agent"
    action_kind: ActionKind | None = ActionKind.VELOCITY

    def __init__(self) -> None:
        self.env: Any = None
        self.rng = np.random.default_rng()

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        """Start an episode in ``env`` (already reset); ``seed`` seeds the agent's own randomness."""
        self.env = env.unwrapped
        self.rng = np.random.default_rng(seed)

    def act(self, observation: Any) -> np.ndarray:
        raise NotImplementedError

    def executed(self, action: Any) -> None:
        """Note that ``action`` was executed in place of this agent's last choice (a learner drove and the
        planner only labels, as in DAgger). A planner that tracks what was driven overrides it; by default an
        agent reads all it needs from the env's belief, so nothing is noted."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


def clip_action(v: float, omega: float) -> np.ndarray:
    """A valid action from (v / v_max, omega / omega_max), clipped to [-1, 1]."""
    return np.array([min(max(v, -1.0), 1.0), min(max(omega, -1.0), 1.0)], dtype=np.float32)


def wall_scan(env: Any, observation: Any) -> np.ndarray:
    """The observation's wall scan in metres (n_beams,), beam i at heading + 2 pi i / n_beams.

    A beam at ``sensor.scan_max_range`` saw no wall. Works for the flat and the Dict observation: the env's
    ``observation_layout`` says where the scan lies.
    """
    normalised = np.asarray(env.observation_layout.part(observation, "scan"), dtype=float)
    return normalised * env.config.sensor.scan_max_range


def beam_angles(n_beams: int) -> np.ndarray:
    """Beam directions (rad) relative to the heading, as the sensor lays them out."""
    return np.arange(n_beams) * (2.0 * math.pi / n_beams)
