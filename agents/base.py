"""The agent interface every baseline and the PPO agent share, and helpers for reading the observation.

An agent is reset with the env at the start of an episode (so a planner can hold on to the env's belief, its
config and the world's bounds) and then maps observations to actions. Nothing here steps the env: the
evaluator owns the loop, so every agent is scored by exactly the same code.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np


class Agent:
    """Base class: ``reset(env, seed)`` once per episode, then ``act(observation) -> action``.

    ``act`` returns a float32 array of shape (2,) in [-1, 1]: (forward speed / v_max, turn rate / omega_max).
    Subclasses that need the belief read ``self.env`` (the unwrapped ``EKFSLAMEnv``: ``filter``, ``config``);
    they must not step it.
    """

    name: str = "agent"

    def __init__(self) -> None:
        self.env: Any = None
        self.rng = np.random.default_rng()

    def reset(self, env: gym.Env, seed: int | None = None) -> None:
        """Start an episode in ``env`` (already reset); ``seed`` seeds the agent's own randomness."""
        self.env = env.unwrapped
        self.rng = np.random.default_rng(seed)

    def act(self, observation: Any) -> np.ndarray:
        raise NotImplementedError

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
