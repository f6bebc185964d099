"""ekfslam-gym: active SLAM as a Gymnasium environment.

Importing the package registers ``EKFSLAM-v0``, ``EKFSLAM-Loop-v0`` and ``EKFSLAM-Large-v0``; both
``gymnasium.make("EKFSLAM-v0")`` after ``import ekfslam_gym`` and ``gymnasium.make("ekfslam_gym:EKFSLAM-v0")``
work.
"""

from gymnasium.envs.registration import register, registry

__version__ = "0.1.0"


def _register() -> None:
    from .envs.presets import PRESETS

    for env_id, overrides in PRESETS.items():
        if env_id not in registry:
            # No max_episode_steps here: the env truncates itself at its config's max_episode_steps, so a
            # config that changes the limit is obeyed (a TimeLimit from the registry would not know it).
            register(
                id=env_id, entry_point="ekfslam_gym.envs.ekfslam_env:EKFSLAMEnv", kwargs={"config": overrides}
            )


_register()
