"""The files the package ships beside its code, found through ``importlib.resources``: the training recipes
(``configs/*.yaml``, package ``ekfslam_gym.configs``), the registered env presets for reading
(``configs/env/*.yaml``, package ``ekfslam_gym.configs.env``, read with ``EnvConfig.from_yaml``) and one trained policy per registered env with its
statistics, training record and versions (``models/``, ``ekfslam_gym.models``).

The repository keeps those folders at its top level; ``setup.py`` maps them into the package, so a wheel, an
editable install and a checkout all find them here, from any working directory.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

CONFIGS = "ekfslam_gym.configs"
ENV_PRESETS = "ekfslam_gym.configs.env"
MODELS = "ekfslam_gym.models"
DEFAULT_CONFIG = "ppo"
CONFIG_SUFFIXES = (".yaml", ".yml")


def _folder(package: str) -> Path:
    """The package's folder on disk (wheels install unzipped, so its data are plain files)."""
    return Path(str(resources.files(package)))


def config_names() -> list[str]:
    """The packaged training recipes, by name (``ppo``, ``ppo_primitives``, ...)."""
    return sorted(p.stem for p in _folder(CONFIGS).glob("*.yaml"))


def resolve_config(name_or_path: str | Path) -> Path:
    """The training config a command line's ``--config`` names: an existing file as given, else a packaged recipe
    by name, with or without ``.yaml`` and with or without the repository's ``configs/`` (so ``ppo``,
    ``ppo.yaml`` and ``configs/ppo.yaml`` all work from any folder). FileNotFoundError names the choices."""
    path = Path(name_or_path)
    if path.is_file():
        return path
    if path.parent in (Path("."), Path("configs")):
        name = path.name if path.suffix in CONFIG_SUFFIXES else f"{path.name}.yaml"
        packaged = _folder(CONFIGS) / name
        if packaged.is_file():
            return packaged
    raise FileNotFoundError(
        f"config {name_or_path} does not exist (neither a file nor a packaged recipe; packaged recipes: "
        f"{', '.join(config_names())})"
    )


def shipped_env_ids() -> list[str]:
    """The env ids with a shipped policy file of their own (``ppo_<env-id>.zip``)."""
    return sorted(p.stem[len("ppo_") :] for p in _folder(MODELS).glob("ppo_*.zip"))


def shipped_model(env_id: str) -> Path:
    """``ppo_<env_id>.zip`` of the shipped policy file for ``env_id`` (its statistics and record lie beside it).
    The policy an id is served by, the generalist's for a v1 layout id, is
    ``ekfslam_gym.pretrained.shipped_policy_file``."""
    env_id = env_id.split(":")[-1]
    path = _folder(MODELS) / f"ppo_{env_id}.zip"
    if not path.is_file():
        raise ValueError(f"no shipped policy for {env_id!r}; shipped: {', '.join(shipped_env_ids())}")
    return path
