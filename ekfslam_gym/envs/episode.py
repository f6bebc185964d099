"""The length of an episode: one rule, in one place (the v1 ids' rule; the v0 ids keep ``horizon.HorizonSync``).

An episode lasts ``step_limit(config)`` env steps:

- ``config.max_episode_steps`` when it is set: a number of env steps (decisions), whatever the action kind;
- otherwise ``config.episode_time`` s of simulated time: ``episode_time / dt`` control steps, divided by the
  action's ``hold`` and rounded up, so every action kind gets the same simulated time (a hold that does not
  divide it lets the last env step run up to ``hold - 1`` control steps past it).

The v1 ids set ``episode_time`` and leave ``max_episode_steps`` unset, and are registered without a step limit
(``env.spec.max_episode_steps`` is None): the env truncates itself at ``step_limit``. The user asks for another
length in env steps with ``gym.make(id, max_episode_steps=N)``, which does what Gymnasium documents (a
``TimeLimit`` of N steps; ``GivenStepLimit`` above it makes the env's own limit, and with it the observation's
time left, N too), or with ``max_episode_steps=N`` in the config; in simulated time with ``episode_time=T``.
Nothing here compares a number with a registered one: a limit is given or it is not.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
from gymnasium.wrappers import TimeLimit


def control_steps(episode_time: float, dt: float) -> int:
    """The control steps of ``dt`` s in ``episode_time`` s (the config holds it to a whole number of dt)."""
    return round(episode_time / dt)


def step_limit(config: Any) -> int:
    """The episode's length in env steps for an ``EnvConfig`` (the module docstring states the rule)."""
    if config.max_episode_steps is not None:
        return config.max_episode_steps
    return -(-control_steps(config.episode_time, config.dt) // config.action.hold)


class GivenStepLimit(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Make the env's own step limit that of a ``TimeLimit`` right below it, if ``gym.make`` was given one.

    For ids registered without a step limit (v1): ``gym.make(id, max_episode_steps=N)`` puts a TimeLimit of N
    under this wrapper, and the env then counts its time left down to N and truncates there too. A different
    ``max_episode_steps`` in the env's config as well is two requests: ``ValueError``. Acts once, at
    construction; ``step`` and ``reset`` pass through.
    """

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        if isinstance(env, TimeLimit):
            base = env.unwrapped
            given = env._max_episode_steps
            own = base.config.max_episode_steps
            if own is not None and own != given:
                raise ValueError(
                    f"two step limits given: max_episode_steps={given} to gym.make and {own} in the env's "
                    "config; give one"
                )
            base.set_max_episode_steps(given)
        gym.Wrapper.__init__(self, env)
