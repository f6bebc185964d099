"""Evaluate agents on a fixed seed suite: per-episode metrics, IQM with bootstrap CIs, tables, plots and GIFs.

Usage::

    python -m ekfslam_gym.evaluate --agent greedy                       # the held-out suite, a text summary
    python -m ekfslam_gym.evaluate --agent ppo --model models/ppo_EKFSLAM-v0.zip --json
    python -m ekfslam_gym.evaluate --compare --model models/ppo_EKFSLAM-v0.zip --table results.md --plot results.png
    python -m ekfslam_gym.evaluate --agent random,circle --seeds 0-9 --max-episode-steps 100 --gif gifs/

Every agent runs the same seeds (``env.reset(seed=s)`` and ``agent.reset(env, seed=s)``), so a comparison is
paired. The default seeds are ``HELD_OUT_SEEDS`` (10000-10049): they are for the final table only, never for
training, hyperparameter search or model selection (train and select on seeds below 10000).

Metrics of one episode (``METRIC_KEYS``): ``return`` (sum of rewards), ``map_log_det`` (log det of the final map
block Sigma_mm, nats), ``pose_log_det`` (log det of the final marginal pose covariance), ``landmark_rmse`` (m,
final estimates of the seen landmarks), ``missed_landmarks`` (never seen), ``seen_fraction``, ``ate`` (m, RMSE of
estimated vs true positions over the steps, no alignment), ``anees`` (the pose NEES averaged over the steps),
``nees_in_bounds`` (fraction of steps whose pose NEES lies within the per-step 95 % chi-squared bounds, ideally
0.95), ``loop_closures``, ``collisions`` (steps in contact with a wall) and ``path_length`` (m, true).
Aggregates are the IQM with a seeded 95 % percentile-bootstrap CI, and the mean; undefined values (NaN) are
left out of the aggregates and written as ``null`` in JSON.

``--json`` prints exactly one JSON object. One agent: ``{"agent": str, "episodes": int, "metrics": {name:
{"iqm": x, "ci": [lo, hi], "mean": x}}}``. Several agents (a comparison): an object keyed by agent name whose
values are such objects, in the order the agents were given.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from ..evaluation import metrics

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
)

# Which way is better, for the table's arrows (None: neither, e.g. ANEES should be near 3, path length is context).
SMOOTHER_KEYS: tuple[str, ...] = ("smoother_ate", "smoother_landmark_rmse")
"""With ``--smoother``: the same episode smoothed by the graph back end (full SLAM), the filter's judge."""

BETTER: dict[str, str | None] = {
    "smoother_ate": "lower",
    "smoother_landmark_rmse": "lower",
    "return": "higher",
    "map_log_det": "lower",
    "pose_log_det": "lower",
    "landmark_rmse": "lower",
    "missed_landmarks": "lower",
    "seen_fraction": "higher",
    "ate": "lower",
    "anees": None,
    "nees_in_bounds": "higher",
    "loop_closures": "higher",
    "collisions": "lower",
    "path_length": None,
}

POSE_DIM = 3
NEES_STEP_BOUNDS = metrics.nees_bounds(POSE_DIM, 1)


# ---------------------------------------------------------------------------------------------------- running
def make_env(
    env_id: str = "EKFSLAM-v0",
    env_kwargs: Mapping[str, Any] | None = None,
    *,
    max_episode_steps: int | None = None,
    render_mode: str | None = None,
) -> gym.Env:
    """``gym.make`` with config overrides; ``max_episode_steps`` goes into the env's config when the registered
    config is a mapping (so the observation's time-left term agrees), else into a TimeLimit."""
    import ekfslam_gym  # noqa: F401  (registers the env ids)

    kwargs = dict(env_kwargs or {})
    limit = None
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
    pose_covs: np.ndarray,
    last_info: Mapping[str, Any],
) -> dict[str, float]:
    """The ``METRIC_KEYS`` of a finished episode from its recorded trajectory and the env's final belief."""
    u = env.unwrapped
    ekf = u.filter
    cov = np.asarray(ekf.cov)
    rmse, missed = metrics.landmark_errors(
        np.asarray(ekf.landmarks), u.true_landmarks, np.asarray(ekf.observed)
    )
    errors = metrics.pose_errors(estimated_poses, true_poses)
    step_nees = metrics.nees(errors, pose_covs)
    return {
        "return": float(total_return),
        "map_log_det": _slogdet(cov[3:, 3:]),
        "pose_log_det": _slogdet(cov[:3, :3]),
        "landmark_rmse": rmse,
        "missed_landmarks": float(missed),
        "seen_fraction": float(np.mean(ekf.observed)) if ekf.n_landmarks else math.nan,
        "ate": metrics.ate(estimated_poses, true_poses),
        "anees": metrics.anees(step_nees),
        "nees_in_bounds": metrics.fraction_in_bounds(step_nees, NEES_STEP_BOUNDS),
        "loop_closures": float(last_info["loop_closures"]),
        "collisions": float(last_info["collisions"]),
        "path_length": float(last_info["path_length"]),
    }


def run_episode(
    env: gym.Env, agent: Any, seed: int, frames: Any = None, smoother: bool = False
) -> dict[str, float]:
    """One seeded episode of ``agent`` in ``env``; appends each rendered frame to ``frames`` if given (a list
    or a ``GifRecorder``); with ``smoother``, also smooths the episode (``SMOOTHER_KEYS``).

    The trajectory metrics use the steps after reset (at reset the estimate is the true pose by construction).
    """
    observation, info = env.reset(seed=seed)
    agent.reset(env, seed=seed)
    recording = None
    if smoother:
        from .smoothing import EpisodeRecorder

        recording = EpisodeRecorder()
        recording.add(info, first=True)
    if frames is not None:
        frames.append(env.render())
    true_poses, estimated_poses, pose_covs = [], [], []
    total, steps = 0.0, 0
    while True:
        observation, reward, terminated, truncated, info = env.step(agent.act(observation))
        total += float(reward)
        steps += 1
        true_poses.append(info["true_pose"])
        estimated_poses.append(info["pose"])
        pose_covs.append(info["pose_cov"])
        if recording is not None:
            recording.add(info)
        if frames is not None:
            frames.append(env.render())
        if terminated or truncated:
            break
    result = episode_metrics(
        env, total, np.array(true_poses), np.array(estimated_poses), np.array(pose_covs), info
    )
    if recording is not None:
        from .smoothing import compare_with_smoother

        compared = compare_with_smoother(recording, env)
        result.update({key: compared[key] for key in SMOOTHER_KEYS})
    return {"seed": int(seed), "steps": steps, **result}


class GifRecorder:
    """Collects every ``stride``-th (H, W, 3) uint8 frame, quantised to a 64-colour palette as it arrives (a
    500-step episode of raw 640 x 640 frames would hold 600 MB), and writes them as one looping GIF."""

    def __init__(self, stride: int = 1, scale: float = 1.0) -> None:
        self.stride = max(int(stride), 1)
        self.scale = float(scale)
        self.images: list[Any] = []
        self._count = 0

    def append(self, frame: np.ndarray) -> None:
        from PIL import Image

        if self._count % self.stride == 0:
            image = Image.fromarray(np.asarray(frame, dtype=np.uint8))
            if self.scale != 1.0:
                size = (max(1, round(image.width * self.scale)), max(1, round(image.height * self.scale)))
                image = image.resize(size, Image.Resampling.LANCZOS)
            self.images.append(image.quantize(colors=64))
        self._count += 1

    def save(self, path: str | Path, fps: float) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        first, *rest = self.images
        duration = int(round(1000.0 * self.stride / fps))
        first.save(path, save_all=True, append_images=rest, duration=duration, loop=0)
        return path


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
) -> list[dict[str, float]]:
    """Run ``agent`` (an ``agents.Agent`` or a registered name) once per seed; one metrics dict per episode.

    Each dict holds ``seed``, ``steps`` and the ``METRIC_KEYS``. With ``gif_dir``, one GIF per episode,
    ``<label>_seed<seed>.gif``, every ``gif_stride``-th frame of ``env.render()``.
    """
    if isinstance(agent, str):
        from agents import make_agent

        agent = make_agent(agent)
    label = label or getattr(agent, "name", type(agent).__name__)
    seeds = [int(s) for s in seeds]
    env = make_env(env_id, env_kwargs, max_episode_steps=max_episode_steps,
                   render_mode="rgb_array" if gif_dir is not None else None)  # fmt: skip
    results = []
    try:
        iterator: Iterable[int] = seeds
        if progress:
            from tqdm import tqdm

            iterator = tqdm(seeds, desc=label, unit="episode", file=sys.stderr, leave=False)
        for seed in iterator:
            recorder = GifRecorder(gif_stride, gif_scale) if gif_dir is not None else None
            results.append(run_episode(env, agent, seed, recorder, smoother=smoother))
            if recorder is not None:
                recorder.save(Path(gif_dir) / f"{label}_seed{seed}.gif", env.metadata.get("render_fps", 10))
    finally:
        env.close()
    return results


def aggregate(
    episodes: Sequence[Mapping[str, float]],
    keys: Sequence[str] = METRIC_KEYS,
    *,
    n_resamples: int = 2000,
    seed: int = 0,
) -> dict[str, dict[str, Any]]:
    """IQM, 95 % bootstrap CI of the IQM (seeded) and mean of each metric over episodes (NaNs left out)."""
    out: dict[str, dict[str, Any]] = {}
    for key in keys:
        values = np.array([float(e[key]) for e in episodes], dtype=float)
        finite = values[np.isfinite(values)]
        lo, hi = metrics.bootstrap_ci(finite, n_resamples=n_resamples, seed=seed)
        out[key] = {
            "iqm": metrics.iqm(finite),
            "ci": [lo, hi],
            "mean": float(finite.mean()) if finite.size else math.nan,
        }
    return out


def summary(agent_name: str, episodes: Sequence[Mapping[str, float]], **kwargs: Any) -> dict[str, Any]:
    """The JSON object of one agent: ``{"agent", "episodes", "metrics"}``."""
    return {"agent": agent_name, "episodes": len(episodes), "metrics": aggregate(episodes, **kwargs)}


def _json_safe(value: Any) -> Any:
    """NaN and inf are not JSON: write them as null."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value


# ---------------------------------------------------------------------------------------------------- reporting
def _fmt(value: float) -> str:
    if value is None or not math.isfinite(value):
        return "n/a"
    magnitude = abs(value)
    if magnitude >= 100:
        return f"{value:.0f}"
    if magnitude >= 10:
        return f"{value:.1f}"
    if magnitude >= 0.1:
        return f"{value:.2f}"
    return f"{value:.3g}"


def markdown_table(summaries: Mapping[str, Mapping[str, Any]], keys: Sequence[str] = METRIC_KEYS) -> str:
    """Agents as rows, metrics as columns, cells ``IQM [lo, hi]``; a note on seeds and NEES bounds below."""
    header = ["agent", "episodes"] + [
        f"{k} {'↑' if BETTER[k] == 'higher' else '↓' if BETTER[k] == 'lower' else ''}".strip() for k in keys
    ]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for name, s in summaries.items():
        cells = [name, str(s["episodes"])]
        for k in keys:
            m = s["metrics"][k]
            cells.append(f"{_fmt(m['iqm'])} [{_fmt(m['ci'][0])}, {_fmt(m['ci'][1])}]")
        lines.append("| " + " | ".join(cells) + " |")
    n = max((s["episodes"] for s in summaries.values()), default=1)
    lo, hi = metrics.nees_bounds(POSE_DIM, max(n, 1))
    lines.append("")
    lines.append(
        f"IQM over episodes [95 % bootstrap CI]. Pose NEES per-step 95 % bounds [{NEES_STEP_BOUNDS[0]:.3f}, "
        f"{NEES_STEP_BOUNDS[1]:.2f}] (nees_in_bounds should be near 0.95); the mean of {n} independent runs' "
        f"NEES lies in [{lo:.2f}, {hi:.2f}] (chi2 bounds, ANEES ideal 3; the time average within an episode "
        "is correlated, so read anees against these only as a guide)."
    )
    return "\n".join(lines) + "\n"


def text_summary(s: Mapping[str, Any]) -> str:
    """A plain-text block for one agent (what the CLI prints without --json)."""
    lines = [
        f"{s['agent']}: {s['episodes']} episodes",
        f"  {'metric':<18}{'IQM':>10}  {'95% CI':<22}{'mean':>10}",
    ]
    for k, m in s["metrics"].items():
        ci = f"[{_fmt(m['ci'][0])}, {_fmt(m['ci'][1])}]"
        lines.append(f"  {k:<18}{_fmt(m['iqm']):>10}  {ci:<22}{_fmt(m['mean']):>10}")
    return "\n".join(lines)


def plot_results(
    episodes: Mapping[str, Sequence[Mapping[str, float]]], path: str | Path, keys: Sequence[str] = METRIC_KEYS
) -> Path:
    """One box plot per metric (episodes per agent), with the IQM and its CI drawn over each box."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    names = list(episodes)
    cols = 4
    rows = int(math.ceil(len(keys) / cols))
    figure = Figure(figsize=(3.2 * cols, 2.6 * rows), layout="constrained")
    FigureCanvasAgg(figure)
    for i, key in enumerate(keys):
        ax = figure.add_subplot(rows, cols, i + 1)
        data = []
        for name in names:
            values = np.array([e[key] for e in episodes[name]], dtype=float)
            data.append(values[np.isfinite(values)])
        positions = np.arange(1, len(names) + 1)
        ax.boxplot(data, positions=positions, widths=0.6, showfliers=True, flierprops={"markersize": 3})
        for p, values in zip(positions, data):
            if values.size:
                centre = metrics.iqm(values)
                lo, hi = metrics.bootstrap_ci(values)
                ax.errorbar([p], [centre], yerr=[[centre - lo], [hi - centre]], fmt="o", color="tab:red",
                            markersize=4, capsize=3)  # fmt: skip
        ax.set_xticks(positions, names, rotation=30, fontsize=8)
        arrow = {"higher": " (higher is better)", "lower": " (lower is better)"}.get(BETTER[key] or "", "")
        ax.set_title(key + arrow, fontsize=9)
        ax.tick_params(axis="y", labelsize=8)
    figure.suptitle("box: episodes; red: IQM with 95 % bootstrap CI", fontsize=9)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    return path


# ---------------------------------------------------------------------------------------------------- CLI
def parse_seeds(text: str) -> list[int]:
    """``A-B`` (inclusive), ``A,B,C``, or a mix such as ``0-4,10``."""
    seeds: list[int] = []
    try:
        for part in filter(None, (p.strip() for p in text.split(","))):
            lo, _, hi = part.partition("-")
            first, last = int(lo), int(hi or lo)
            if last < first:
                raise argparse.ArgumentTypeError(f"empty seed range {part!r}")
            seeds.extend(range(first, last + 1))
    except ValueError:
        raise argparse.ArgumentTypeError(f"seeds must look like A-B or A,B,C, got {text!r}") from None
    if not seeds:
        raise argparse.ArgumentTypeError(f"no seeds in {text!r}")
    return seeds


def _build_parser() -> argparse.ArgumentParser:
    from agents import AGENTS

    parser = argparse.ArgumentParser(
        prog="python -m ekfslam_gym.evaluate",
        description="Evaluate agents on a seed suite (default: the held-out seeds 10000-10049).",
    )
    parser.add_argument("--agent", default=None,
                        help=f"an agent or a comma-separated list (a comparison); one of {', '.join(AGENTS)}")  # fmt: skip
    parser.add_argument("--compare", action="store_true",
                        help="compare random, circle, lawnmower, greedy (and ppo when --model is given)")  # fmt: skip
    parser.add_argument("--model", action="append", default=[],
                        help="saved PPO model (<model>.zip, statistics in <model>_vecnormalize.pkl); repeat it for "
                             "several training seeds, whose episodes are pooled into one 'ppo' row "
                             "unless --per-model")  # fmt: skip
    parser.add_argument(
        "--per-model", action="store_true", help="one row per --model instead of pooling them"
    )
    parser.add_argument("--env-id", default="EKFSLAM-v0")
    parser.add_argument("--env-kwargs", type=json.loads, default=None,
                        help='config overrides as JSON, e.g. \'{"world": {"n_landmarks": 50}}\'')  # fmt: skip
    parser.add_argument("--agent-kwargs", type=json.loads, default=None,
                        help='constructor arguments per agent as JSON, e.g. \'{"circle": {"radius": 2.0}}\'')  # fmt: skip
    parser.add_argument("--seeds", type=parse_seeds, default=list(HELD_OUT_SEEDS),
                        help="A-B (inclusive) or A,B,C; default the held-out suite 10000-10049")  # fmt: skip
    parser.add_argument("--max-episode-steps", type=int, default=None, help="shorter episodes (smoke tests)")
    parser.add_argument("--json", action="store_true", help="print exactly one JSON object to stdout")
    parser.add_argument("--gif", metavar="DIR", default=None, help="write one GIF per episode to DIR")
    parser.add_argument("--gif-stride", type=int, default=2, help="keep every n-th frame in GIFs")
    parser.add_argument("--gif-scale", type=float, default=1.0, help="resize GIF frames by this factor")
    parser.add_argument("--plot", metavar="FILE", default=None, help="box plots of every metric")
    parser.add_argument("--table", metavar="FILE.md", default=None, help="markdown table of the aggregates")
    parser.add_argument("--episodes-json", metavar="FILE", default=None, help="write the per-episode metrics")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars on stderr")
    parser.add_argument("--smoother", action="store_true",
                        help="also smooth every episode with graph SLAM and report smoother_ate and "
                             "smoother_landmark_rmse beside the filter's ate and landmark_rmse")  # fmt: skip
    return parser


def _agent_entries(args: argparse.Namespace, parser: argparse.ArgumentParser) -> list[tuple[str, list[Any]]]:
    """(row label, agents whose episodes form that row); several agents in a row only for pooled PPO models."""
    from agents import AGENTS, BASELINES, make_agent

    if args.compare:
        names = list(BASELINES) + (["ppo"] if args.model else [])
    elif args.agent:
        names = [n.strip() for n in args.agent.split(",") if n.strip()]
    else:
        parser.error("give --agent NAME[,NAME...] or --compare")
    unknown = [n for n in names if n not in AGENTS]
    if unknown:
        parser.error(f"unknown agent(s) {unknown}; choose from {sorted(AGENTS)}")
    if len(set(names)) != len(names):
        parser.error("an agent is listed twice")
    per_agent = args.agent_kwargs or {}
    if not isinstance(per_agent, dict) or any(not isinstance(v, dict) for v in per_agent.values()):
        parser.error(
            '--agent-kwargs must be a JSON object keyed by agent name, e.g. \'{"circle": {"radius": 2}}\''
        )
    entries = []
    for name in names:
        kwargs = dict(per_agent.get(name, {}))
        if name == "ppo":
            if not args.model:
                parser.error("the ppo agent needs --model PATH")
            models = [make_agent("ppo", model_path=path, **kwargs) for path in args.model]
            if args.per_model and len(models) > 1:
                entries += [(f"ppo[{Path(p).with_suffix('').name}]", [m]) for p, m in zip(args.model, models)]
            else:
                entries.append(("ppo", models))
        else:
            entries.append((name, [make_agent(name, **kwargs)]))
    return entries


def main(argv: Sequence[str] | None = None) -> int:
    parser = _build_parser()
    args = parser.parse_args(argv)
    entries = _agent_entries(args, parser)
    if any(label.startswith("ppo") for label, _ in entries):
        import torch

        torch.set_num_threads(1)  # small MLP policies: threads only contend with the other cores' work

    for _, agent_list in entries:
        for agent in agent_list:
            trained_id = getattr(agent, "trained_env_id", None)
            trained_kwargs = getattr(agent, "trained_env_kwargs", None)
            if trained_id is not None and trained_id.split(":")[-1] != args.env_id.split(":")[-1]:
                print(
                    f"warning: {agent!r} was trained on {trained_id}, evaluated on {args.env_id}",
                    file=sys.stderr,
                )
            if trained_kwargs is not None and dict(trained_kwargs) != dict(args.env_kwargs or {}):
                print(
                    f"warning: {agent!r} was trained with env_kwargs {trained_kwargs}, evaluated with "
                    f"{args.env_kwargs or {}} (pass --env-kwargs to match)",
                    file=sys.stderr,
                )

    episodes: dict[str, list[dict[str, float]]] = {}
    for label, agent_list in entries:
        rows: list[dict[str, float]] = []
        for k, agent in enumerate(agent_list):
            tag = label if len(agent_list) == 1 else f"{label}{k}"
            rows += evaluate_agent(
                agent, args.env_id, args.seeds, args.env_kwargs, max_episode_steps=args.max_episode_steps,
                gif_dir=args.gif, gif_stride=args.gif_stride, gif_scale=args.gif_scale, label=tag,
                progress=not args.no_progress,
                smoother=args.smoother,
            )  # fmt: skip
        episodes[label] = rows
    keys = METRIC_KEYS + (SMOOTHER_KEYS if args.smoother else ())
    summaries = {label: summary(label, rows, keys=keys) for label, rows in episodes.items()}

    if args.table:
        path = Path(args.table)
        path.parent.mkdir(parents=True, exist_ok=True)
        seeds = args.seeds
        held_out = " (the held-out suite)" if list(seeds) == list(HELD_OUT_SEEDS) else ""
        path.write_text(
            f"`{args.env_id}`, seeds {seeds[0]}-{seeds[-1]}{held_out}, {len(seeds)} episodes per agent.\n\n"
            + markdown_table(summaries, keys)
        )
    if args.plot:
        plot_results(episodes, args.plot, keys)
    if args.episodes_json:
        Path(args.episodes_json).write_text(json.dumps(_json_safe(episodes), indent=1))

    if args.json:
        out: Any = next(iter(summaries.values())) if len(summaries) == 1 else summaries
        print(json.dumps(_json_safe(out), allow_nan=False))
    else:
        print(f"{args.env_id}, {len(args.seeds)} seeds ({args.seeds[0]}..{args.seeds[-1]})")
        for s in summaries.values():
            print(text_summary(s))
        print(f"pose NEES per-step 95 % bounds: [{NEES_STEP_BOUNDS[0]:.3f}, {NEES_STEP_BOUNDS[1]:.2f}]")
        if len(summaries) > 1:
            print()
            print(markdown_table(summaries, keys), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
