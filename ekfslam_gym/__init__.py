"""ekfslam-gym: active SLAM as a Gymnasium environment.

Importing the package registers ``EKFSLAM-v0``, ``EKFSLAM-Loop-v0`` and ``EKFSLAM-Large-v0``; both
``gymnasium.make("EKFSLAM-v0")`` after ``import ekfslam_gym`` and ``gymnasium.make("ekfslam_gym:EKFSLAM-v0")``
work.
"""

from gymnasium.envs.registration import WrapperSpec, register, registry

__version__ = "0.1.0"


def _register() -> None:
    from .envs.config import EnvConfig
    from .envs.presets import PRESETS

    for env_id, overrides in PRESETS.items():
        if env_id not in registry:
            # The spec carries the preset's step limit (gym.make's TimeLimit), and HorizonSync, right above
            # that TimeLimit, makes the env's own limit (truncation, time left) the same number whichever of
            # gym.make(max_episode_steps=N) or the config gives it (see ekfslam_gym.envs.horizon).
            limit = EnvConfig.from_overrides(**overrides).max_episode_steps
            sync = WrapperSpec(
                name="HorizonSync",
                entry_point="ekfslam_gym.envs.horizon:HorizonSync",
                kwargs={"registered_limit": limit},
            )
            # The env builds the preset itself: ``config=`` then merges onto it, ``preset=None`` replaces it.
            register(
                id=env_id,
                entry_point="ekfslam_gym.envs.ekfslam_env:EKFSLAMEnv",
                max_episode_steps=limit,
                additional_wrappers=(sync,),
                kwargs={"preset": env_id},
            )


_register()
