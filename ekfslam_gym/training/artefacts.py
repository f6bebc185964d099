"""What a training run leaves in its folder: models saved with their normalisation statistics and the run's
record, checkpoints with the random state, the record itself (``config.yaml``, ``versions.json``), the
demonstrations a run cloned, and the learning curve from SB3's monitor logs. The file names, and the parser of
the record that every reader shares, are ``ekfslam_gym.artefacts``'.

The folder's files (``ekfslam_gym.training.run`` writes them):

- ``model.zip`` + ``model_vecnormalize.pkl``: the final policy and its normalisation statistics;
- ``best_model.zip`` + ``best_model_vecnormalize.pkl``: the best on the evaluation seeds (with ``eval_freq`` above
  0; when no evaluation fell inside the run, the final model evaluated once at its end);
- ``checkpoints/``: ``ppo_<steps>_steps.zip`` with ``..._vecnormalize.pkl`` and ``..._rng.pkl`` (random state);
- ``config.yaml`` (the resolved entry and command line) and ``versions.json``, copied beside every model as
  ``<model>_config.yaml`` and ``<model>_versions.json``;
- ``tb/`` tensorboard logs, ``monitor/`` episode logs, ``evaluations.npz`` and ``learning_curve.png``;
- with ``pretrain``: ``bc_model.zip`` (+ statistics, config, versions), the cloned policy before any PPO update;
  ``demonstrations.npz`` (``dagger.npz`` with DAgger rounds) and ``pretrain.json`` (settings, accuracies).
"""

from __future__ import annotations

import json
import pickle
import platform
import random
import sys
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

from ekfslam_gym.artefacts import (  # noqa: F401  (read_run: the command line reads it here)
    DAGGER_FILE,
    DEMONSTRATIONS_FILE,
    EVALUATIONS_FILE,
    LEARNING_CURVE_FILE,
    MONITOR,
    RECORD_FILE,
    VERSIONS_FILE,
    ModelFiles,
    RunRecord,
    checkpoint_files,
    read_run,
)

from .demonstrations import Demonstrations, load


def versions() -> dict[str, str]:
    found = {"python": platform.python_version()}
    for name in (
        "ekfslam-gym",
        "numpy",
        "scipy",
        "numba",
        "pymunk",
        "gymnasium",
        "stable-baselines3",
        "sb3-contrib",
        "torch",
    ):
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "not installed"
    return found


def write_record(
    out: Path, env_id: str, seed: int, entry: Mapping[str, Any], command: list[str] | None
) -> None:
    """Create the run folder with its record: ``config.yaml`` (env id, seed, the resolved entry and the command
    line that repeats the run) and ``versions.json``."""
    out.mkdir(parents=True, exist_ok=True)
    (out / RECORD_FILE).write_text(RunRecord(env_id, seed, dict(entry)).to_yaml(command))
    (out / VERSIONS_FILE).write_text(json.dumps(versions(), indent=2))


def save_with_stats(model, stem: Path, run: Path) -> None:
    """``stem.zip``, ``stem_vecnormalize.pkl`` if the model normalises (the convention the agents load), and the
    run's record and package versions beside it as ``stem_config.yaml`` and ``stem_versions.json``."""
    files = ModelFiles(Path(stem))
    files.stem.parent.mkdir(parents=True, exist_ok=True)
    model.save(str(files.zip))
    normalizer = model.get_vec_normalize_env()
    if normalizer is not None:
        normalizer.save(str(files.vecnormalize))
    files.record.write_text((run / RECORD_FILE).read_text())
    files.versions.write_text((run / VERSIONS_FILE).read_text())


def save_checkpoint(model, run: Path, steps: int) -> None:
    """The model at ``steps`` env steps in ``checkpoints/``, with the random state to resume from."""
    import numpy as np
    import torch

    files = checkpoint_files(run, steps)
    save_with_stats(model, files.stem, run)
    # SB3 draws from the legacy global numpy RNG, so that is the state to keep.
    state = {"python": random.getstate(), "numpy": np.random.get_state(), "torch": torch.get_rng_state()}  # noqa: NPY002
    with open(files.rng, "wb") as handle:
        pickle.dump(state, handle)


def run_demonstrations(out: Path, pretrain: Mapping[str, Any]) -> Demonstrations:
    """The demonstrations a run was cloned on: its DAgger set, else those it collected, else ``pretrain.path``."""
    for candidate in (Path(out) / DAGGER_FILE, Path(out) / DEMONSTRATIONS_FILE):
        if candidate.is_file():
            return load(candidate)
    if pretrain.get("path"):
        return load(pretrain["path"])
    raise FileNotFoundError(
        f"{out} holds no demonstrations ({DAGGER_FILE} or {DEMONSTRATIONS_FILE}) to keep cloning"
    )


def read_monitor(folder: Path):
    """(return, length, wall time) of every finished training episode in SB3's monitor CSVs (no pandas)."""
    import numpy as np

    rows = []
    for path in sorted(Path(folder).rglob("*.monitor.csv")):
        lines = (
            path.read_text().splitlines()
        )  # '#{json header with t_start}', 'r,l,t', then one row an episode
        if len(lines) < 3:
            continue
        t_start = json.loads(lines[0].lstrip("#"))["t_start"]
        for line in lines[2:]:
            r, length, t = (float(v) for v in line.split(",")[:3])
            rows.append([r, length, t_start + t])
    return np.array(rows).reshape(-1, 3)


def plot_learning_curve(out: Path) -> Path | None:
    """Training episode returns (from the monitor logs) and evaluation returns against env steps."""
    import numpy as np

    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        print("matplotlib is not installed: no learning-curve plot", file=sys.stderr)
        return None
    fig = Figure(figsize=(7, 4))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    episodes = read_monitor(out / MONITOR)
    if len(episodes):
        order = np.argsort(episodes[:, 2])
        returns, steps = episodes[order, 0], np.cumsum(episodes[order, 1])
        window = max(1, len(returns) // 20)
        smooth = np.convolve(returns, np.ones(window) / window, mode="valid")
        ax.plot(steps[window - 1 :], smooth, label=f"training (mean of {window} episodes)")
    evaluations = out / EVALUATIONS_FILE
    if evaluations.is_file():
        data = np.load(evaluations)
        ax.errorbar(data["timesteps"], data["results"].mean(axis=1), yerr=data["results"].std(axis=1),
                    fmt="o-", label="evaluation seeds")  # fmt: skip
    ax.set_xlabel("env steps")
    ax.set_ylabel("episode return")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend()
    else:
        ax.text(0.5, 0.5, "no finished episode yet", transform=ax.transAxes, ha="center")
    path = out / LEARNING_CURVE_FILE
    fig.savefig(path, dpi=100, bbox_inches="tight")
    return path
