"""The files a training run leaves and the code that reads them back: every file name in one place, a saved
model's companion files, and the one parser of the run's record.

The trainer (``ekfslam_gym.training``) writes these names and the agents, the evaluator and ``load_pretrained``
read them, so both sides take them from here:

- a saved model is ``<stem>.zip`` with, beside it, ``<stem>_vecnormalize.pkl`` (the VecNormalize statistics,
  when observations were normalised), ``<stem>_config.yaml`` (the run's record) and ``<stem>_versions.json``
  (``ModelFiles``); a checkpoint also has ``<stem>_rng.pkl`` (the random state);
- a run folder holds ``config.yaml`` (the record) and ``versions.json``, the models ``model``, ``best_model``
  and ``bc_model``, ``checkpoints/ppo_<steps>_steps``, ``evaluations.npz``, ``pretrain.json``,
  ``demonstrations.npz``, ``dagger.npz``, ``learning_curve.png`` and the ``monitor/`` and ``tb/`` logs;
- the record (``RunRecord``) is YAML: ``env_id``, ``seed``, ``entry`` (the resolved config entry, with its
  ``env_kwargs`` and ``algo``) and ``argv`` (the command line that repeats the run).

No third-party import but YAML's, so the lightest reader can use it.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

MODEL = "model"  # the final policy
BEST_MODEL = "best_model"  # the best on the evaluation seeds
BC_MODEL = "bc_model"  # the cloned policy, before any PPO update
MODEL_SUFFIX = ".zip"
VECNORMALIZE_SUFFIX = "_vecnormalize.pkl"
RECORD_SUFFIX = "_config.yaml"
VERSIONS_SUFFIX = "_versions.json"
RNG_SUFFIX = "_rng.pkl"
RECORD_FILE = "config.yaml"  # the run folder's record
VERSIONS_FILE = "versions.json"
CHECKPOINTS = "checkpoints"
CHECKPOINT_NAME = re.compile(r"ppo_(\d+)_steps")
EVALUATIONS_FILE = "evaluations.npz"
PRETRAIN_FILE = "pretrain.json"
DEMONSTRATIONS_FILE = "demonstrations.npz"
DAGGER_FILE = "dagger.npz"  # the demonstrations and every DAgger round's pairs, when there were rounds
LEARNING_CURVE_FILE = "learning_curve.png"
MONITOR = "monitor"
TENSORBOARD = "tb"


@dataclass(frozen=True)
class ModelFiles:
    """A saved model's files, from its stem (the path without ``.zip``)."""

    stem: Path

    @classmethod
    def of(cls, path: str | Path) -> ModelFiles:
        """The files of the model at ``path``, given with or without ``.zip``."""
        path = Path(path)
        return cls(path.with_suffix("") if path.suffix == MODEL_SUFFIX else path)

    def _beside(self, suffix: str) -> Path:
        return self.stem.with_name(self.stem.name + suffix)

    @property
    def zip(self) -> Path:
        return self._beside(MODEL_SUFFIX)

    @property
    def vecnormalize(self) -> Path:
        return self._beside(VECNORMALIZE_SUFFIX)

    @property
    def record(self) -> Path:
        return self._beside(RECORD_SUFFIX)

    @property
    def versions(self) -> Path:
        return self._beside(VERSIONS_SUFFIX)

    @property
    def rng(self) -> Path:
        return self._beside(RNG_SUFFIX)


def model_paths(path: str | Path) -> tuple[Path, Path]:
    """(``<model>.zip``, ``<model>_vecnormalize.pkl``) for a model path given with or without ``.zip``."""
    files = ModelFiles.of(path)
    return files.zip, files.vecnormalize


def checkpoint_files(run: Path, steps: int) -> ModelFiles:
    """The files of the checkpoint taken at ``steps`` env steps in the run folder ``run``."""
    return ModelFiles(Path(run) / CHECKPOINTS / f"ppo_{int(steps)}_steps")


def latest_checkpoint(folder: Path) -> tuple[Path, int] | None:
    """(the ``.zip``, its steps) of the latest checkpoint in ``folder`` (a run's ``checkpoints/``), or None."""
    found = []
    for path in Path(folder).glob(f"ppo_*_steps{MODEL_SUFFIX}"):
        match = CHECKPOINT_NAME.fullmatch(path.name[: -len(MODEL_SUFFIX)])
        if match:
            found.append((int(match.group(1)), path))
    if not found:
        return None
    steps, path = max(found)
    return path, steps


class RunRecord(NamedTuple):
    """A run's record (``config.yaml``), parsed: what a resume continues and what a saved model was trained on.
    A record written by hand may lack the env id or the seed (None); the entry is {} when absent."""

    env_id: str | None
    seed: int | None
    entry: dict[str, Any]

    @property
    def env_kwargs(self) -> dict[str, Any] | None:
        """The training env's ``env_kwargs`` (None when the record has none)."""
        kwargs = self.entry.get("env_kwargs")
        return dict(kwargs) if isinstance(kwargs, Mapping) else None

    @property
    def algo(self) -> str:
        """The algorithm's name (``ekfslam_gym.agents.ppo.ALGOS``); absent means ``ppo``."""
        return str(self.entry.get("algo", "ppo"))

    @property
    def policy_kwargs(self) -> dict[str, Any] | None:
        """The policy's keyword arguments as recorded (class names dotted), or None."""
        kwargs = self.entry.get("policy_kwargs")
        return dict(kwargs) if isinstance(kwargs, Mapping) else None

    def to_yaml(self, argv: list[str] | None = None) -> str:
        """The record as the trainer writes it, with the command line ``argv`` that repeats the run."""
        import yaml

        data = {"env_id": self.env_id, "seed": self.seed, "entry": dict(self.entry), "argv": list(argv or [])}
        return yaml.safe_dump(data, sort_keys=False)

    @classmethod
    def parse(cls, text: str, source: str | Path = "<record>") -> RunRecord:
        """The record in ``text`` (YAML); ValueError naming ``source`` when it is no record."""
        import yaml

        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as error:
            raise ValueError(f"{source}: not a readable training record ({error})") from None
        if not isinstance(data, Mapping):
            raise ValueError(
                f"{source}: a training record is a mapping of env_id, seed and entry, got {data!r}"
            )
        env_id, seed, entry = data.get("env_id"), data.get("seed"), data.get("entry", {})
        if env_id is not None and not isinstance(env_id, str):
            raise ValueError(f"{source}: env_id must be an env id, got {env_id!r}")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
            raise ValueError(f"{source}: seed must be an integer, got {seed!r}")
        if not isinstance(entry, Mapping):
            raise ValueError(f"{source}: entry must be a mapping of settings, got {entry!r}")
        return cls(env_id, seed, dict(entry))

    @classmethod
    def read(cls, path: str | Path) -> RunRecord:
        """The record in the file ``path``; FileNotFoundError when it is missing, ValueError when malformed."""
        path = Path(path)
        return cls.parse(path.read_text(), path)


def read_run(folder: str | Path) -> RunRecord:
    """The record of the run folder ``folder``, complete (env id and seed), as ``--resume`` continues it;
    FileNotFoundError when the folder has none, ValueError when it lacks the env id or the seed."""
    path = Path(folder) / RECORD_FILE
    if not path.is_file():
        raise FileNotFoundError(f"{folder} is not a training run folder (no {RECORD_FILE})")
    record = RunRecord.read(path)
    missing = [name for name in ("env_id", "seed") if getattr(record, name) is None]
    if missing:
        raise ValueError(f"{path}: the record has no {' or '.join(missing)}")
    return record


def record_beside(model: str | Path) -> RunRecord | None:
    """The record of the run a saved model came from: ``<model>_config.yaml`` beside it, else its folder's
    ``config.yaml``; None when there is none or it cannot be read (a model saved by hand)."""
    files = ModelFiles.of(model)
    path = files.record if files.record.is_file() else files.stem.parent / RECORD_FILE
    if not path.is_file():
        return None
    try:
        return RunRecord.read(path)
    except (OSError, ValueError):
        return None
