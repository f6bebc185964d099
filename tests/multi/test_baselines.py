"""The team baselines (``ekfslam_gym.multi.baselines``): random, independent nearest-frontier robots and
Burgard et al.'s coordinated frontier assignment."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("pettingzoo")

from ekfslam_gym.agents.frontier import FrontierPrimitivesPlanner  # noqa: E402

from ekfslam_gym.envs import EKFSLAMEnv  # noqa: E402
from ekfslam_gym.multi import parallel_env  # noqa: E402
from ekfslam_gym.multi.baselines import (  # noqa: E402
    CoordinatedFrontierTeam,
    IndependentFrontierTeam,
    RandomTeam,
    RobotView,
    utility_cost_assignment,
)
from ekfslam_gym.multi.evaluation import run_episode  # noqa: E402


def test_random_team_is_valid_and_seeded():
    team = parallel_env(n_robots=3, max_episode_steps=5)
    observations, _ = team.reset(seed=0)
    first, second = RandomTeam(), RandomTeam()
    first.reset(team, seed=4)
    second.reset(team, seed=4)
    a, b = first.act(observations), second.act(observations)
    assert a == b and set(a) == set(team.agents)
    assert all(team.action_space(agent).contains(action) for agent, action in a.items())


def test_robot_view_is_one_robots_belief():
    team = parallel_env(n_robots=2, max_episode_steps=5)
    team.reset(seed=1)
    view = RobotView(team, 1)
    np.testing.assert_array_equal(view.filter.pose, team.filter.pose(1))
    np.testing.assert_array_equal(view.filter.pose_cov, team.filter.pose_cov(1))
    assert view.unwrapped is view and view.coverage_memory.shape == team.coverage_memory.shape


def test_one_independent_robot_is_the_single_robot_frontier_planner():
    """With one robot the team env is the single-robot env bit for bit, so the independent frontier team acts
    exactly as the single-robot planner does there."""
    team = parallel_env(n_robots=1, max_episode_steps=15)
    single = EKFSLAMEnv(preset=None, action={"kind": "primitives"}, max_episode_steps=15)
    team_obs, _ = team.reset(seed=10)
    single_obs, _ = single.reset(seed=10)
    team_agent, planner = IndependentFrontierTeam(), FrontierPrimitivesPlanner()
    team_agent.reset(team, seed=0)
    planner.reset(single, seed=0)
    for _ in range(15):
        team_action = team_agent.act(team_obs)["robot_0"]
        single_action = planner.act(single_obs)
        assert team_action == int(single_action)
        team_obs, _, _, truncated, _ = team.step({"robot_0": team_action})
        single_obs, *_ = single.step(single_action)
        if truncated["robot_0"]:
            break


def test_assignment_sends_robots_apart():
    """Two robots both near frontier A (cost 1 m) and far from B (10 m), A and B 20 m apart: nearest-frontier
    robots would both take A; the utility-cost assignment gives A to one and B to the other, since A's utility
    is spent once it is taken."""
    costs = np.array([[1.0, 10.0], [1.5, 10.5]])
    targets = np.array([[0.0, 0.0], [20.0, 0.0]])
    assert utility_cost_assignment(costs, targets, beta=0.05, reach=6.0) == [0, 1]
    # 2 m from A, B keeps a third of its utility (2 / 6), less than the 9 m more it costs (x 0.05): both take A
    near = np.array([[0.0, 0.0], [2.0, 0.0]])
    assert utility_cost_assignment(costs, near, beta=0.05, reach=6.0) == [0, 0]


def test_assignment_with_costs_dominating_is_greedy_nearest():
    rng = np.random.default_rng(0)
    costs = rng.uniform(1, 30, (3, 40))
    targets = rng.uniform(0, 20, (40, 2))
    chosen = utility_cost_assignment(costs, targets, beta=1e3, reach=6.0)
    first = int(np.argmin(costs.min(axis=1)))  # the cheapest pair of all is taken first
    assert chosen[first] == int(np.argmin(costs[first]))


def test_assignment_with_utility_dominating_spreads_out():
    rng = np.random.default_rng(1)
    costs = rng.uniform(1, 30, (3, 200))
    targets = rng.uniform(0, 40, (200, 2))
    chosen = utility_cost_assignment(costs, targets, beta=1e-9, reach=6.0)
    points = targets[chosen]
    gaps = np.hypot(*(points[:, None] - points[None]).transpose(2, 0, 1))
    assert gaps[~np.eye(3, dtype=bool)].min() >= 6.0


def test_unreachable_targets_are_never_assigned():
    costs = np.array([[np.inf, 3.0], [np.inf, np.inf]])
    assert utility_cost_assignment(costs, np.zeros((2, 2)), 0.05, 6.0) == [1, -1]


def test_coordinated_team_assigns_distinct_frontiers():
    team = parallel_env(n_robots=3, max_episode_steps=5)
    observations, _ = team.reset(seed=3)
    agent = CoordinatedFrontierTeam()
    agent.reset(team, seed=0)
    agent.act(observations)
    targets = agent.assign(observations)
    assert len(targets) == 3 and None not in targets and len(set(targets)) == 3


@pytest.mark.parametrize("agent", [RandomTeam(), IndependentFrontierTeam(), CoordinatedFrontierTeam()])
def test_baselines_run_an_episode(agent):
    team = parallel_env(n_robots=3, max_episode_steps=6)
    metrics = run_episode(team, agent, seed=7)
    assert metrics["time_to_complete"] > 0 and math.isfinite(metrics["map_log_det"])
    assert 0 < metrics["landmarks_seen"] <= 30
