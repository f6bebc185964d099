"""One step limit for the TimeLimit wrapper and the env.

``gym.make`` truncates an episode with a ``TimeLimit`` wrapper, while the env's observation counts its time
left down to the env's own ``config.max_episode_steps``, and the env truncates itself there too (so an env
built without ``gym.make`` still ends). The registered ids apply ``HorizonSync`` right above the TimeLimit to
make the two one number N of env steps, decided so:

- nothing given: the registered limit R (the preset's: 500, 800, 1000 control steps of 0.1 s), divided by
  ``action.hold``, rounded up, so that an episode lasts the same simulated time whatever the action kind: e.g.
  ``gym.make("EKFSLAM-v0", action={"kind": "primitives"})`` holds each primitive for 10 control steps and
  gets 50 env steps, the velocity env's 50 s; a hold that does not divide R gives the episode up to hold - 1
  more control steps, with a warning;
- ``gym.make(id, max_episode_steps=N)``: the env's config is set to N (``EKFSLAMEnv.set_max_episode_steps``);
- ``gym.make(id, config=...)`` or an override such as ``gym.make(id, world=..., config={"max_episode_steps":
  N})`` whose limit differs from the registered one: the TimeLimit is rebuilt with N;
- both, different from each other and each from the registered limit: ``ValueError`` (no silent choice);
- ``gym.make(id, max_episode_steps=-1)`` (no TimeLimit): the env truncates itself at its config's limit.

A limit equal to the registered one counts as not given (the two cannot be told apart). Then
``env.spec.max_episode_steps``, ``env.unwrapped.config.max_episode_steps``, the step at which ``truncated`` is
first true and the step at which the time-left feature reaches 0 are all N.
"""

from __future__ import annotations

import gymnasium as gym
from gymnasium.wrappers import TimeLimit


def limit_for_hold(registered_limit: int, hold: int) -> int:
    """The env steps that last as long as ``registered_limit`` control steps when each holds ``hold``."""
    return -(-registered_limit // hold)


class HorizonSync(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Make the TimeLimit below it and the EKFSLAM env agree on the step limit (see the module docstring).

    ``registered_limit`` is the id's registered ``max_episode_steps``, in control steps: a limit equal to it
    counts as not given. It acts once, at construction, and passes ``step`` and ``reset`` through untouched.
    """

    def __init__(self, env: gym.Env, registered_limit: int) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, registered_limit=registered_limit)
        base = env.unwrapped
        own = base.config.max_episode_steps
        spec = env.spec if isinstance(env, TimeLimit) else None
        limit = spec.max_episode_steps if spec is not None else None
        limit_given = limit is not None and limit != registered_limit
        own_given = own != registered_limit
        if limit_given and own_given and limit != own:
            raise ValueError(
                f"two step limits given: max_episode_steps={limit} to gym.make and {own} in the env's "
                "config; give one"
            )
        if not limit_given and not own_given:
            # Neither given: the registered time, in env steps of this action kind.
            hold = base.config.action.hold
            own = limit_for_hold(registered_limit, hold)
            if registered_limit % hold:
                gym.logger.warn(
                    f"action.hold {hold} does not divide the registered {registered_limit}-step limit: the "
                    f"episode gets {own} env steps ({own * hold} control steps); pass max_episode_steps to "
                    "choose another"
                )
            if own != registered_limit:
                base.set_max_episode_steps(own)
        elif limit_given and limit != own:
            base.set_max_episode_steps(limit)
            own = limit
        if limit is not None and own != limit:
            # The same class as gym.make's: rl-zoo3, once imported, replaces gymnasium's TimeLimit by its own
            # subclass, and a base TimeLimit would then no longer pickle (its name resolves to the subclass).
            env = type(env)(env.env, own)
        gym.Wrapper.__init__(self, env)
