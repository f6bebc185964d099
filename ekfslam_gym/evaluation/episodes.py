"""Running agents in the env: the env factory, the one episode loop, per-episode metrics, and the recorder of
what the graph smoother needs.

Every agent runs the same seeds (``env.reset(seed=s)`` and ``agent.reset(env, seed=s)``), so a comparison is
paired. ``HELD_OUT_SEEDS`` (10000-10049) are for the final table only, never for training, hyperparameter
search or model selection (train and select on seeds below 10000).

Metrics of one episode (``METRIC_KEYS``): ``return`` (sum of rewards), ``map_log_det`` (log det of the final map
block Sigma_mm, nats), ``pose_log_det`` (log det of the final marginal pose covariance), ``landmark_rmse`` (m,
final estimates of the seen landmarks), ``missed_landmarks`` (never seen), ``seen_fraction``, ``ate`` (m, RMSE of
estimated vs true positions over the steps, no alignment), ``anees`` (the pose NEES averaged over the steps),
``nees_in_bounds`` (fraction of steps whose pose NEES lies within the per-step 95 % chi-squared bounds, ideally
0.95), ``loop_closures``, ``collisions`` (steps in contact with a wall), ``path_length`` (m, true), and belief
beside truth (``BELIEF_KEYS``, one value per episode, aggregated over episodes like every metric: IQM and CI,
not pooled):

- ``belief_truth_pearson`` and ``belief_truth_spearman``: the correlation over the episode's env steps of
  ``info["belief_gain"]`` (the drop of the seen landmarks' position variances, what the filter believes the map
  gained) and ``info["truth_gain"]`` (the drop of their squared errors, what it gained; both m^2 over the same
  landmarks, the env's docstring defines them). Low: the steps the filter believes informative are not those
  that make the map better. The drop of ``info["log_det"]`` (the reward's information gain) is not correlated
  with the truth gain here: its steps are ruled by discoveries (about 20 nats each, while a new landmark's error
  enters the truth gain only from the next step) and by the pose's prediction noise, so its Pearson
  correlation is about 0 for every agent (README, "Belief beside truth") and tells none apart: not reported.
- ``map_nees``: the NEES of the seen landmarks' final estimates jointly, e_m^T Sigma_mm^-1 e_m, divided by its
  2 n_seen degrees of freedom (as in ``consistency``): about 1 for a consistent filter, above 1 when the filter
  believes its map better than it is (the over-confidence a reward for believed information pays for). Chosen
  over the ratio sum(belief_gain) / sum(truth_gain), which divides by a noisy sum that can be near 0 or below
  (a map made no better): under consistency the NEES is chi2(2 n_seen) / (2 n_seen), its spread known.

With unknown data association (``filter.association`` not ``known``) also ``ASSOCIATION_KEYS``, the episode's
``false_associations`` and ``missed_associations``, and the map metrics score each filter slot against the
true landmark it holds (``env.slot_truth``): a landmark is missed when no slot holds it.

``export_tum`` writes an episode's true and estimated trajectories and its map for the evo tools
(``data.tum``).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from . import metrics
from .consistency import map_nees
from .gif import GifRecorder
from .smoothing import compare_with_smoother

HELD_OUT_SEEDS: tuple[int, ...] = tuple(range(10000, 10050))
"""The held-out evaluation suite. Never train, tune or select models on these seeds."""

METRIC_KEYS: tuple[str, ...] = (
    "return",
    "map_log_det",
    "pose_log_det",
    "landmark_rmse",
    "missed_landmarks",
    "seen_fraction",
    "ate",
    "anees",
    "nees_in_bounds",
    "loop_closures",
    "collisions",
    "path_length",
    "belief_truth_pearson",
    "belief_truth_spearman",
    "map_nees",
)

BELIEF_KEYS: tuple[str, ...] = ("belief_truth_pearson", "belief_truth_spearman", "map_nees")
"""Belief beside truth, part of ``METRIC_KEYS`` (the module docstring defines them)."""

ASSOCIATION_KEYS: tuple[str, ...] = ("false_associations", "missed_associations")
"""With unknown data association: the env's counts over the episode (``EKFSLAMEnv``'s docstring)."""

SMOOTHER_KEYS: tuple[str, ...] = ("smoother_ate", "smoother_landmark_rmse")
"""With ``smoother``: the same episode smoothed by the graph back end (full SLAM), the filter's judge."""

POSE_DIM = 3
NEES_STEP_BOUNDS = metrics.nees_bounds(POSE_DIM, 1)


@dataclass
class EpisodeRecorder:
    """Collects one episode from ``reset`` and ``step`` infos (odometry model only: the smoother's edges)."""

    true_poses: list = field(default_factory=list)
    filter_poses: list = field(default_factory=list)
    odometry: list = field(default_factory=list)
    odometry_cov: list = field(default_factory=list)
    readings: list = field(default_factory=list)

    def add(self, info: dict[str, Any], *, first: bool = False) -> None:
        """Add the info of ``reset`` (``first=True``: no odometry yet) or of a ``step``."""
        if not first:
            if len(info["odometry"]) != 3:
                raise ValueError(
                    "the smoother needs the odometry motion model (filter.motion_model='odometry')"
                )
            self.odometry.append(np.asarray(info["odometry"], dtype=float))
            self.odometry_cov.append(np.asarray(info["odometry_cov"], dtype=float))
        self.true_poses.append(np.asarray(info["true_pose"], dtype=float))
        self.filter_poses.append(np.asarray(info["pose"], dtype=float))
        ids, z = info["readings"]
        self.readings.append(
            np.column_stack([np.asarray(ids, dtype=float), np.asarray(z, dtype=float)]).reshape(-1, 3)
        )


def make_env(
    env_id: str = "EKFSLAM-v0",
    env_kwargs: Mapping[str, Any] | None = None,
    *,
    max_episode_steps: int | None = None,
    render_mode: str | None = None,
) -> gym.Env:
    """``gym.make`` with config overrides; ``max_episode_steps`` (the argument, else one among ``env_kwargs``, as
    a training record holds it) goes into the env's config when the registered config is a mapping (so the
    observation's time-left term agrees), else into a TimeLimit."""
    import ekfslam_gym  # noqa: F401  (registers the env ids)

    kwargs = dict(env_kwargs or {})
    limit = None
    recorded = kwargs.pop("max_episode_steps", None)
    if max_episode_steps is None:
        max_episode_steps = recorded
    if max_episode_steps is not None:
        base = kwargs.get("config", gym.spec(env_id).kwargs.get("config"))
        if base is None or isinstance(base, Mapping):
            kwargs["config"] = {**(base or {}), "max_episode_steps": int(max_episode_steps)}
        else:
            limit = int(max_episode_steps)
    if render_mode is not None:
        kwargs["render_mode"] = render_mode
    return gym.make(env_id, max_episode_steps=limit, **kwargs)


def _slogdet(matrix: np.ndarray) -> float:
    if matrix.size == 0:
        return 0.0
    if not np.all(np.isfinite(matrix)):
        return math.nan
    sign, value = np.linalg.slogdet(matrix)
    return float(value) if sign > 0 else math.nan


def episode_metrics(
    env: gym.Env,
    total_return: float,
    true_poses: np.ndarray,
    estimated_poses: np.ndarray,
    step_nees: np.ndarray,
    last_info: Mapping[str, Any],
    belief_gains: np.ndarray,
    truth_gains: np.ndarray,
) -> dict[str, float]:
    """The ``METRIC_KEYS`` of a finished episode from its recorded trajectory, the pose NEES the env reported at
    each step (``info["pose_nees"]``), the per-step belief and truth gains (``info["belief_gain"]``,
    ``info["truth_gain"]``) and the env's final belief."""
    u = env.unwrapped
    ekf = u.filter
    cov = np.asarray(ekf.cov)
    unknown = u.config.filter.association != "known"
    if unknown:
        truth = np.asarray(u.slot_truth)
        held = np.asarray(ekf.observed) & (truth >= 0)
        true_landmarks = u.true_landmarks[np.maximum(truth, 0)]
        rmse, _ = metrics.landmark_errors(np.asarray(ekf.landmarks), true_landmarks, held)
        missed = ekf.n_landmarks - np.unique(truth[held]).size
        seen_fraction = 1.0 - missed / ekf.n_landmarks if ekf.n_landmarks else math.nan
    else:
        held, true_landmarks = np.asarray(ekf.observed), u.true_landmarks
        rmse, missed = metrics.landmark_errors(np.asarray(ekf.landmarks), true_landmarks, held)
        seen_fraction = float(np.mean(ekf.observed)) if ekf.n_landmarks else math.nan
    value, dof = map_nees(np.asarray(ekf.mean), cov, held, true_landmarks)
    result = {
        "return": float(total_return),
        "map_log_det": _slogdet(cov[3:, 3:]),
        "pose_log_det": _slogdet(cov[:3, :3]),
        "landmark_rmse": rmse,
        "missed_landmarks": float(missed),
        "seen_fraction": seen_fraction,
        "ate": metrics.ate(estimated_poses, true_poses),
        "anees": metrics.anees(step_nees),
        "nees_in_bounds": metrics.fraction_in_bounds(step_nees, NEES_STEP_BOUNDS),
        "loop_closures": float(last_info["loop_closures"]),
        "collisions": float(last_info["collisions"]),
        "path_length": float(last_info["path_length"]),
    }
    pearson, spearman = metrics.gain_correlation(belief_gains, truth_gains)
    result["belief_truth_pearson"], result["belief_truth_spearman"] = pearson, spearman
    result["map_nees"] = value / dof if dof else math.nan
    if unknown:
        result.update({key: float(last_info[key]) for key in ASSOCIATION_KEYS})
    return result


def run_episode(
    env: gym.Env,
    agent: Any,
    seed: int,
    frames: Any = None,
    recording: EpisodeRecorder | None = None,
    trajectories: Callable[[np.ndarray, np.ndarray], object] | None = None,
) -> dict[str, float]:
    """One seeded episode of ``agent`` in ``env``: its metrics (``seed``, ``steps`` and ``METRIC_KEYS``).

    Appends each rendered frame to ``frames`` if given (a list or a ``GifRecorder``) and the odometry and
    readings of every step to ``recording`` if given (what the graph smoother needs). The trajectory metrics
    use the steps after reset (at reset the estimate is the true pose by construction); ``trajectories``, if
    given, is called once at the end, the env still in its final state, with those (T, 3) true and estimated
    poses (e.g. ``export_tum``).
    """
    observation, info = env.reset(seed=seed)
    agent.reset(env, seed=seed)
    if recording is not None:
        recording.add(info, first=True)
    if frames is not None:
        frames.append(env.render())
    true_poses, estimated_poses, step_nees = [], [], []
    belief_gains, truth_gains = [], []
    total, steps = 0.0, 0
    while True:
        observation, reward, terminated, truncated, info = env.step(agent.act(observation))
        total += float(reward)
        steps += 1
        true_poses.append(info["true_pose"])
        estimated_poses.append(info["pose"])
        step_nees.append(info["pose_nees"])
        belief_gains.append(info["belief_gain"])
        truth_gains.append(info["truth_gain"])
        if recording is not None:
            recording.add(info)
        if frames is not None:
            frames.append(env.render())
        if terminated or truncated:
            break
    true, estimated = np.array(true_poses, dtype=float), np.array(estimated_poses, dtype=float)
    if trajectories is not None:
        trajectories(true, estimated)
    result = episode_metrics(
        env, total, true, estimated, np.array(step_nees, dtype=float), info, np.array(belief_gains, dtype=float),
        np.array(truth_gains, dtype=float),
    )  # fmt: skip
    return {"seed": int(seed), "steps": steps, **result}


def export_tum(
    directory: str | Path, label: str, seed: int, env: gym.Env, true: np.ndarray, estimated: np.ndarray
) -> list[Path]:
    """Write an episode for the evo tools: ``<label>_<seed>_true.tum`` and ``<label>_<seed>_estimate.tum`` (the
    (T, 3) poses after each step t = 1..T, stamped t * dt s: the ones ``ate`` scores, so evo's APE without
    alignment is that ATE) and ``<label>_<seed>_landmarks.csv`` (the env's final map by slot; ``data.tum``)."""
    from ..data.tum import write_landmarks_csv, write_tum

    u = env.unwrapped
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    stem = directory / f"{label}_{seed}"
    timestamps = np.arange(1, len(true) + 1) * float(u.config.dt)
    ekf = u.filter
    return [
        write_tum(f"{stem}_true.tum", timestamps, true),
        write_tum(f"{stem}_estimate.tum", timestamps, estimated),
        write_landmarks_csv(f"{stem}_landmarks.csv", u.true_landmarks, ekf.landmarks, ekf.observed),
    ]


def evaluate_agent(
    agent: Any,
    env_id: str = "EKFSLAM-v0",
    seeds: Iterable[int] = HELD_OUT_SEEDS,
    env_kwargs: Mapping[str, Any] | None = None,
    *,
    max_episode_steps: int | None = None,
    gif_dir: str | Path | None = None,
    gif_stride: int = 2,
    gif_scale: float = 1.0,
    label: str | None = None,
    progress: bool = False,
    smoother: bool = False,
    tum_dir: str | Path | None = None,
) -> list[dict[str, float]]:
    """Run ``agent`` (an ``agents.Agent`` or a registered name) once per seed; one metrics dict per episode.

    Each dict holds ``seed``, ``steps`` and the ``METRIC_KEYS``. With ``gif_dir``, one GIF per episode,
    ``<label>_seed<seed>.gif``, every ``gif_stride``-th frame of ``env.render()``; with ``smoother``, also the
    ``SMOOTHER_KEYS`` of the episode smoothed by the graph back end; with ``tum_dir``, the files of
    :func:`export_tum` for every episode.
    """
    if isinstance(agent, str):
        from ekfslam_gym.agents import make_agent

        agent = make_agent(agent)
    label = label or getattr(agent, "name", type(agent).__name__)
    seeds = [int(s) for s in seeds]
    env = make_env(env_id, env_kwargs, max_episode_steps=max_episode_steps,
                   render_mode="rgb_array" if gif_dir is not None else None)  # fmt: skip
    results = []
    try:
        iterator: Iterable[int] = seeds
        if progress and getattr(sys.stderr, "isatty", lambda: False)():  # a bar only on a terminal, not a log
            from tqdm import tqdm

            iterator = tqdm(seeds, desc=label, unit="episode", file=sys.stderr, leave=False)
        for seed in iterator:
            frames = GifRecorder(gif_stride, gif_scale) if gif_dir is not None else None
            recording = EpisodeRecorder() if smoother else None
            export = partial(export_tum, tum_dir, label, seed, env) if tum_dir is not None else None
            result = run_episode(env, agent, seed, frames, recording, export)
            if recording is not None:
                compared = compare_with_smoother(recording, env)
                result.update({key: compared[key] for key in SMOOTHER_KEYS})
            results.append(result)
            if frames is not None:
                frames.save(Path(gif_dir) / f"{label}_seed{seed}.gif", env.metadata.get("render_fps", 10))
    finally:
        env.close()
    return results
