"""One step limit for the TimeLimit wrapper and the env.

``gym.make`` truncates an episode with a ``TimeLimit`` wrapper, while the env's observation counts its time
left down to the env's own ``config.max_episode_steps``, and the env truncates itself there too (so an env
built without ``gym.make`` still ends). The registered ids apply ``HorizonSync`` right above the TimeLimit to
make the two one number N, decided so:

- nothing given: the registered limit (the preset's: 500, 800, 1000), which is also the config's;
- ``gym.make(id, max_episode_steps=N)``: the env's config is set to N (``EKFSLAMEnv.set_max_episode_steps``);
- ``gym.make(id, config=...)`` or an override such as ``gym.make(id, world=..., config={"max_episode_steps":
  N})`` whose limit differs from the registered one: the TimeLimit is rebuilt with N;
- both, different from each other and each from the registered limit: ``ValueError`` (no silent choice);
- ``gym.make(id, max_episode_steps=-1)`` (no TimeLimit): the env truncates itself at its config's limit.

Then ``env.spec.max_episode_steps``, ``env.unwrapped.config.max_episode_steps``, the step at which
``truncated`` is first true and the step at which the time-left feature reaches 0 are all N.
"""

from __future__ import annotations

import gymnasium as gym
from gymnasium.wrappers import TimeLimit


class HorizonSync(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Make the TimeLimit below it and the EKFSLAM env agree on the step limit (see the module docstring).

    ``registered_limit`` is the id's registered ``max_episode_steps``: a limit equal to it counts as not given.
    It acts once, at construction, and passes ``step`` and ``reset`` through untouched.
    """

    def __init__(self, env: gym.Env, registered_limit: int) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, registered_limit=registered_limit)
        base = env.unwrapped
        own = base.config.max_episode_steps
        spec = env.spec if isinstance(env, TimeLimit) else None
        limit = spec.max_episode_steps if spec is not None else None
        if limit is not None and limit != own:
            limit_given, own_given = limit != registered_limit, own != registered_limit
            if limit_given and own_given:
                raise ValueError(
                    f"two step limits given: max_episode_steps={limit} to gym.make and {own} in the env's "
                    "config; give one"
                )
            if own_given:
                # The same class as gym.make's: rl-zoo3, once imported, replaces gymnasium's TimeLimit by its own
                # subclass, and a base TimeLimit would then no longer pickle (its name resolves to the subclass).
                env = type(env)(env.env, own)
            else:
                base.set_max_episode_steps(limit)
        gym.Wrapper.__init__(self, env)
