"""ekfslam-gym: active SLAM as a Gymnasium environment.

Importing the package registers every id of ``ekfslam_gym.envs.presets.PRESETS`` (``EKFSLAM-v0``,
``EKFSLAM-Loop-v0``, ``EKFSLAM-Large-v0`` and their v1 versions, a v1 id per layout family, and
``EKFSLAM-Mix-v1``); both ``gymnasium.make("EKFSLAM-v1")`` after ``import ekfslam_gym`` and
``gymnasium.make("ekfslam_gym:EKFSLAM-v1")`` work.

The shipped policies and any saved model's env (``ekfslam_gym.pretrained``, needs the ``train`` extra):
``load_pretrained(env_id)``, ``make_env_for_model(path)`` and ``load_model(path)``, imported on first use.
"""

import sys
from pathlib import Path
from typing import Any

from gymnasium.envs.registration import WrapperSpec, register, registry

__version__ = "0.3.0"  # the package's version (pyproject.toml reads it from here); CHANGELOG.md


def _register() -> None:
    from .envs.config import EnvConfig
    from .envs.presets import PRESETS, registered_entry_point

    for env_id, overrides in PRESETS.items():
        if env_id in registry:
            continue
        limit = EnvConfig.from_overrides(**overrides).max_episode_steps
        if limit is None:
            # v1: the env's length is its config's (ekfslam_gym.envs.episode), no TimeLimit unless gym.make is
            # given max_episode_steps, and then GivenStepLimit makes the env's own limit that number too.
            wrapper = WrapperSpec(
                name="GivenStepLimit", entry_point="ekfslam_gym.envs.episode:GivenStepLimit", kwargs={}
            )
        else:
            # v0: the spec carries the preset's step limit (gym.make's TimeLimit), and HorizonSync, right above
            # that TimeLimit, makes the env's own limit (truncation, time left) the same number whichever of
            # gym.make(max_episode_steps=N) or the config gives it (see ekfslam_gym.envs.horizon).
            wrapper = WrapperSpec(
                name="HorizonSync",
                entry_point="ekfslam_gym.envs.horizon:HorizonSync",
                kwargs={"registered_limit": limit},
            )
        # The env builds the preset itself: ``config=`` then merges onto it, ``preset=None`` replaces it.
        register(
            id=env_id,
            entry_point=registered_entry_point(env_id),
            max_episode_steps=limit,
            additional_wrappers=(wrapper,),
            kwargs={"preset": env_id},
        )


_register()

# The folders setup.py maps into the package from the checkout's top level (``agents/``, ``models/``,
# ``configs/``): an install puts them inside it, an editable install's finder serves them from the checkout.
MAPPED_PACKAGES = ("ekfslam_gym.agents", "ekfslam_gym.models", "ekfslam_gym.configs")


class _UnmappedSourceTree:
    """Last on ``sys.meta_path``, so asked only when no finder has ``ekfslam_gym.agents`` (models, configs):
    the package was then imported from a source tree that no install mapped, e.g. the checkout's own folder
    shadowing a regular install when Python runs from the checkout's root. Says so instead of a bare
    ``No module named``."""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> None:
        if fullname in MAPPED_PACKAGES:
            here = Path(__file__).resolve().parent
            folder = fullname.split(".")[1]
            raise ModuleNotFoundError(
                f"no module named {fullname!r}: the ekfslam_gym imported from {here} is a source tree without "
                f"its {folder}/ folder, which setup.py maps into the package at install. Install the checkout "
                f"editable (pip install -e {here.parent}), or run from outside the checkout to use the "
                "installed package.",
                name=fullname,
            )
        return None


if not any(type(finder).__name__ == _UnmappedSourceTree.__name__ for finder in sys.meta_path):
    sys.meta_path.append(_UnmappedSourceTree())

_LAZY = {
    "load_pretrained": "ekfslam_gym.pretrained",
    "make_env_for_model": "ekfslam_gym.pretrained",
    "load_model": "ekfslam_gym.agents.ppo",
}


def __getattr__(name: str) -> Any:
    """The loaders of ``_LAZY``, imported when first used (they pull torch and stable-baselines3)."""
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'ekfslam_gym' has no attribute {name!r}")
