"""Judge the online filter by the full-SLAM optimum of the same episode.

An env's ``info`` carries, every step, the odometry with its covariance and the readings (and at reset the
first readings), which is all a graph needs. ``EpisodeRecorder`` collects them; ``compare_with_smoother``
smooths the episode with ``slam.smoother`` and reports the filter's and the smoother's ATE and landmark RMSE.

    python -m ekfslam_gym.smoothing [--env-id EKFSLAM-v0] [--seeds 10000-10004] [--agent circle] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..evaluation.metrics import ate, landmark_errors
from ..graph.smoother import smooth_drive


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


def compare_with_smoother(recorder: EpisodeRecorder, env, method: str = "gn") -> dict[str, float]:
    """Filter vs smoother on the recorded episode: ATE (m, no alignment, over the steps after reset: at reset both
    start at the true pose) and landmark RMSE of the landmarks each estimated (m). ``env`` is the env the episode
    ran in, still at its last step."""
    env = env.unwrapped
    config = env.config
    true_poses = np.array(recorder.true_poses)
    smoothed = smooth_drive(
        true_poses[0], np.array(recorder.odometry), np.array(recorder.odometry_cov), recorder.readings,
        config.sensor.cov, initial_pose_cov=config.filter.pose_prior * np.eye(3),
        num_landmarks=env.filter.n_landmarks, method=method,
    )  # fmt: skip
    truth = env.true_landmarks
    filter_rmse, _ = landmark_errors(np.asarray(env.filter.landmarks), truth, np.asarray(env.filter.observed))
    smoother_seen = ~np.isnan(smoothed.landmarks[:, 0])
    smoother_rmse, _ = landmark_errors(np.nan_to_num(smoothed.landmarks), truth, smoother_seen)
    return {
        "steps": len(recorder.odometry),
        "filter_ate": ate(np.array(recorder.filter_poses)[1:, :2], true_poses[1:, :2]),
        "smoother_ate": ate(smoothed.poses[1:, :2], true_poses[1:, :2]),
        "filter_landmark_rmse": filter_rmse,
        "smoother_landmark_rmse": smoother_rmse,
        "smoother_iterations": smoothed.result.iterations,
        "smoother_seconds": smoothed.result.seconds,
    }


def run_episode(env, agent, seed: int) -> EpisodeRecorder:
    """One episode of ``agent`` (an ``agents.Agent``) in ``env``, recorded."""
    recorder = EpisodeRecorder()
    obs, info = env.reset(seed=seed)
    agent.reset(env.unwrapped, seed)
    recorder.add(info, first=True)
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(agent.act(obs))
        recorder.add(info)
        done = terminated or truncated
    return recorder


def main(argv: list[str] | None = None) -> int:
    import gymnasium as gym

    import ekfslam_gym  # noqa: F401
    from agents import make_agent

    from .evaluate import parse_seeds

    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env-id", default="EKFSLAM-v0")
    parser.add_argument("--agent", default="circle")
    parser.add_argument("--seeds", default="10000-10004")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    rows = []
    for seed in parse_seeds(args.seeds):
        env = gym.make(args.env_id)
        recorder = run_episode(env, make_agent(args.agent), seed)
        rows.append({"seed": seed, **compare_with_smoother(recorder, env)})
    if args.json:
        print(json.dumps(rows))
        return 0
    print(
        f"{'seed':>6} {'steps':>5} | {'filter ATE':>10} {'smoother':>9} | {'filter lm RMSE':>14} {'smoother':>9}"
    )
    for r in rows:
        print(f"{r['seed']:>6} {r['steps']:>5} | {r['filter_ate']:>10.4f} {r['smoother_ate']:>9.4f} | "
              f"{r['filter_landmark_rmse']:>14.4f} {r['smoother_landmark_rmse']:>9.4f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
