"""Many robots, one map: the team env (``ekfslam_team_v0``), made as PettingZoo's own envs are.

``parallel_env(n_robots=3, ...)`` is the ``ParallelEnv``; ``env()`` the AEC form (PettingZoo's
``parallel_to_aec`` with its usual wrappers) and ``raw_env()`` the AEC form unwrapped. ``TeamSLAMEnv``'s
docstring describes the env; ``TeamEnvConfig`` its configuration. Importing this package registers the env with
PettingZoo's registry as ``EKFSLAM-Team-v0`` (``pettingzoo.make("parallel", "EKFSLAM-Team-v0", n_robots=3)``, and
``"aec"`` for the AEC form).
"""

from pettingzoo import register

from .config import TeamConfig, TeamEnvConfig, build_team_config
from .env import TeamSLAMEnv, env, parallel_env, raw_env

ENV_ID = "EKFSLAM-Team-v0"
register("parallel", ENV_ID, entry_point="ekfslam_gym.multi.env:parallel_env")
register("aec", ENV_ID, entry_point="ekfslam_gym.multi.env:env")

__all__ = [
    "TeamConfig",
    "TeamEnvConfig",
    "TeamSLAMEnv",
    "build_team_config",
    "env",
    "parallel_env",
    "raw_env",
]
