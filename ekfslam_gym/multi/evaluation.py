"""Team episodes and their metrics, aggregated as the single-robot tables are (IQM with a 95 % bootstrap CI,
``ekfslam_gym.evaluation.aggregate``).

Per episode: the team's final map log det (ln det Sigma_mm, the joint covariance's map block: the map the team
leaves, whatever its poses), the landmarks' RMS position error, the time to a complete map (control steps
until every landmark's marginal standard deviation is below ``done_std``, which ends the episode; an episode
that never gets there counts its full length, and ``complete`` says whether it did), robot-to-robot loop
closures (two robots reading each other after at least ``loop_gap`` control steps apart), landmark loop
closures, wall contacts of all robots, and the return.

    python -m ekfslam_gym.cli.team_evaluate coordinated --robots 3 --seeds heldout --out runs/coordinated3.json
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..evaluation.aggregate import aggregate
from .env import TeamSLAMEnv, parallel_env

TEAM_METRICS = (
    "map_log_det",
    "map_rmse",
    "time_to_complete",
    "complete",
    "robot_loop_closures",
    "loop_closures",
    "landmarks_seen",
    "collisions",
    "return",
)


def map_log_det(team: TeamSLAMEnv) -> float:
    """ln det Sigma_mm of the team's joint covariance: ln det Sigma - ln det P (P the poses given the map)."""
    ekf = team.filter
    return float(ekf.log_det - np.linalg.slogdet(ekf.pose_cov_given_map)[1])


def run_episode(team: TeamSLAMEnv, agent: Any, seed: int) -> dict[str, float]:
    """One seeded episode of ``agent`` (``reset(team, seed)``, ``act(observations)``) and its metrics."""
    observations, _ = team.reset(seed=seed)
    agent.reset(team, seed)
    total, terminated, infos = 0.0, False, {}
    while team.agents:
        observations, rewards, terminations, _, infos = team.step(agent.act(observations))
        total += next(iter(rewards.values()))
        terminated = any(terminations.values())
    last = next(iter(infos.values()))
    complete = terminated and not last["filter_failed"]
    return {
        "seed": seed,
        "map_log_det": map_log_det(team),
        "map_rmse": float(last["map_rmse"]),
        "time_to_complete": float(last["step"]),
        "complete": float(complete),
        "robot_loop_closures": float(last["robot_loop_closures"]),
        "loop_closures": float(last["loop_closures"]),
        "landmarks_seen": float(last["landmarks_seen"]),
        "collisions": float(sum(info["collisions"] for info in infos.values())),
        "return": total,
    }


def evaluate(
    make_agent: Callable[[], Any], n_robots: int, seeds: Sequence[int], **env_kwargs: Any
) -> list[dict[str, float]]:
    """Episodes of a fresh ``make_agent()`` on ``n_robots`` robots, one per seed."""
    team = parallel_env(n_robots=n_robots, **env_kwargs)
    return [run_episode(team, make_agent(), seed) for seed in seeds]


def summarise(episodes: Sequence[dict[str, float]]) -> dict[str, dict[str, Any]]:
    """IQM, 95 % bootstrap CI and mean of every team metric."""
    return aggregate(episodes, TEAM_METRICS)


def make_agent(name: str, model: str | None = None) -> Callable[[], Any]:
    """A factory of the team agent ``name``: random, independent, coordinated or ppo (``model`` its zip)."""
    from .baselines import CoordinatedFrontierTeam, IndependentFrontierTeam, RandomTeam

    factories: dict[str, Callable[[], Any]] = {
        "random": RandomTeam,
        "independent": IndependentFrontierTeam,
        "coordinated": CoordinatedFrontierTeam,
    }
    if name == "ppo":
        if model is None:
            raise ValueError("agent ppo needs --model (a team policy's zip)")
        from .training import TeamPolicy

        policy = TeamPolicy(model)
        return lambda: policy
    if name not in factories:
        raise ValueError(f"agent must be one of {sorted([*factories, 'ppo'])}, got {name!r}")
    return factories[name]
