"""Running agents in the env: the env factory, the one episode loop, and ``evaluate_agent`` over a seed list.

Every agent runs the same seeds (``env.reset(seed=s)`` and ``agent.reset(env, seed=s)``), so a comparison is
paired. Which seeds are for what is ``ekfslam_gym.seeds``: ``evaluate_agent`` defaults to the evaluation seeds
(``EVAL_SEEDS``, 20000-20049); the held-out suite (``HELD_OUT_SEEDS``, 10000-10049) is for the final table only
and is asked for by passing it. The metrics of an episode are ``episode_metrics``'s, the smoother's judge
``smoothing``'s and the TUM export ``export``'s.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Mapping
from functools import partial
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from ..seeds import EVAL_SEEDS
from .episode_metrics import episode_metrics
from .export import export_tum
from .gif import GifRecorder
from .interface import check_action_kind
from .smoothing import SMOOTHER_KEYS, EpisodeRecorder, compare_with_smoother


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


def merge_env_kwargs(
    trained: Mapping[str, Any] | None, overrides: Mapping[str, Any] | None
) -> dict[str, Any]:
    """A trained policy's recorded env settings with command-line ``--env-kwargs`` on top, section by section:
    ``{"filter": {"variant": "fej"}}`` changes the variant and keeps the rest of the record's ``filter``."""
    merged: dict[str, Any] = {
        key: dict(v) if isinstance(v, Mapping) else v for key, v in (trained or {}).items()
    }
    for key, value in (overrides or {}).items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    return merged


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
    check_action_kind(agent, env)
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


def evaluate_agent(
    agent: Any,
    env_id: str = "EKFSLAM-v0",
    seeds: Iterable[int] = EVAL_SEEDS,
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
    """Run ``agent`` (anything with ``reset(env, seed)`` and ``act(observation)``, e.g. an
    ``ekfslam_gym.agents.Agent``) once per seed of ``seeds`` (default the evaluation seeds 20000-20049; pass
    ``ekfslam_gym.seeds.HELD_OUT_SEEDS`` for the final table); one metrics dict per episode.

    Each dict holds ``seed``, ``steps`` and the ``METRIC_KEYS``. With ``gif_dir``, one GIF per episode,
    ``<label>_seed<seed>.gif``, every ``gif_stride``-th frame of ``env.render()``; with ``smoother``, also the
    ``SMOOTHER_KEYS`` of the episode smoothed by the graph back end; with ``tum_dir``, the files of
    :func:`export_tum` for every episode.
    """
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
