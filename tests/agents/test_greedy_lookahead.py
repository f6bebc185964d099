"""The greedy planner's two-step lookahead (depth=2, the ``greedy2`` agent): depth 1 is the planner as it was, and
a depth-2 score is the first primitive's score plus the best second primitive's, continued from its end."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from ekfslam_gym.agents import AGENTS, GreedyInfoGainAgent, GreedyLookaheadAgent, make_agent, wall_scan
from ekfslam_gym.agents.greedy.rollout import rollout
from ekfslam_gym.agents.navigation import count_new, scan_geometry, to_world

import ekfslam_gym  # noqa: F401  (registers the env ids)
from tests.agent_runs import agent_actions


def _actions(agent, seed=3, steps=40, env_id="EKFSLAM-v0"):
    return agent_actions(agent, seed, steps, env_id)[0]


@pytest.fixture
def mid_episode():
    """A depth-1 greedy agent 30 steps into a seeded episode, with the state its next plan starts from."""
    env = gym.make("EKFSLAM-v0")
    observation, _ = env.reset(seed=2)
    agent = GreedyInfoGainAgent()
    agent.reset(env, seed=2)
    for _ in range(30):
        observation, *_ = env.step(agent.act(observation))
    u = env.unwrapped
    pose = np.asarray(u.filter.pose, dtype=float)
    points, segments = scan_geometry(wall_scan(u, observation), agent._angles, agent._scan_max)
    yield env, agent, observation, pose, points, segments
    env.close()


def test_registry_and_defaults():
    assert AGENTS["greedy2"] is GreedyLookaheadAgent and make_agent("greedy2").depth == 2
    assert make_agent("greedy").depth == 1 and make_agent("greedy2", discount=0.5).discount == 0.5


@pytest.mark.parametrize(
    "kwargs", [{"depth": 0}, {"depth": 3}, {"depth": 1.5}, {"depth": "2"}, {"depth": True}, {"discount": -0.1},
               {"discount": 1.5}, {"discount": float("nan")}],
)  # fmt: skip
def test_bad_depth_or_discount_is_refused(kwargs):
    with pytest.raises(ValueError, match="depth|discount"):
        GreedyInfoGainAgent(**kwargs)


def test_depth_one_is_the_default_planner():
    assert np.array_equal(_actions(GreedyInfoGainAgent(depth=1)), _actions(GreedyInfoGainAgent()))


def test_depth_two_is_deterministic_under_a_seed():
    first = _actions(make_agent("greedy2"), seed=5, steps=25)
    assert np.array_equal(first, _actions(make_agent("greedy2"), seed=5, steps=25))
    assert np.all(np.isfinite(first)) and np.all(np.abs(first) <= 1.0)


def test_planning_leaves_the_env_filter_alone(mid_episode):
    env, agent, observation, *_ = mid_episode
    ekf = env.unwrapped.filter
    agent.depth = 2
    before = (np.array(ekf.mean).tobytes(), np.array(ekf.cov).tobytes(), ekf.log_det)
    agent._left = 0  # plan on this call
    agent.act(observation)
    assert (np.array(ekf.mean).tobytes(), np.array(ekf.cov).tobytes(), ekf.log_det) == before


def test_two_step_score_is_the_one_step_score_plus_the_best_continuation(mid_episode):
    """Known answer: each first primitive's depth-2 score = its depth-1 score + discount * max over second
    primitives of (expected gain from the first's rolled-forward belief + discovery of cells neither the
    state's grid nor the first covered + frontier progress from the first's end), second paths that would
    hit the scanned walls left out; written out here from the planner's pieces."""
    env, agent, _, pose, points, segments = mid_episode
    ekf = env.unwrapped.filter
    agent._plan(pose, points, segments)
    one = agent.last_scores.copy()
    agent.depth, agent.discount = 2, 0.7
    agent._plan(pose, points, segments)
    two = agent.last_scores.copy()

    open_cells = agent._open_unlooked()
    done = ~open_cells
    n_unseen = ekf.n_landmarks - np.count_nonzero(ekf.observed)
    per_cell = agent._nats * n_unseen / np.count_nonzero(open_cells)
    assert n_unseen > 0  # the discovery and frontier terms are in play
    field = agent._frontier_field(open_cells)
    b, sensing = agent._bounds, (agent._min_range, agent._max_range, agent._fov)

    def covered(world, seen):
        stamp = np.zeros(done.shape, dtype=np.int64)
        n = count_new(seen, stamp, 1, b[0], b[1], agent.cell, world, 0.0, agent._max_range, 0.5 * agent._fov)
        return n, stamp == 1

    checked = vetoed_second = 0
    assert np.array_equal(np.isinf(one), np.isinf(two))
    for i, (controls, covs, rel) in enumerate(agent._plans):
        if not np.isfinite(one[i]):
            continue
        sim = rollout(ekf, controls, covs, *sensing)
        end = to_world(rel[-1:], pose)[0]
        _, first_cells = covered(to_world(rel[1:], pose), done)
        seconds = []
        for controls2, covs2, rel2 in agent._plans:
            if agent._vetoed(to_world(rel2, rel[-1]), pose, points, segments):
                vetoed_second += 1
                continue
            gain = sim.log_det - rollout(sim, controls2, covs2, *sensing).log_det
            world2 = to_world(rel2[1:], end)
            new, _ = covered(world2, done | first_cells)
            progress = agent._lookup(field, end) - agent._lookup(field, world2[-1])
            assert np.isfinite(progress)  # an unexplored cell is reachable, so the frontier term counts
            seconds.append(gain + agent.discovery_weight * per_cell * new + agent.frontier_weight * progress)
        assert two[i] == pytest.approx(one[i] + 0.7 * max(seconds), rel=1e-9, abs=1e-9)
        checked += 1
    assert checked >= 3


def test_second_steps_into_a_scanned_wall_are_vetoed(mid_episode):
    """Driving straight twice towards a wall 2.5 m ahead: the first leg (1.5 m at full speed) is allowed, the
    second leg from its end is not, while turning in place there is."""
    env, agent, *_ = mid_episode
    beams = agent._angles
    with np.errstate(divide="ignore"):
        scan = np.where(np.cos(beams) > 0.05, 2.5 / np.cos(beams), np.inf)
    scan = np.minimum(scan, env.unwrapped.config.sensor.scan_max_range)
    points, segments = scan_geometry(scan, beams, agent._scan_max)
    pose = np.array([10.0, 10.0, 0.0])
    straight = next(i for i, (v, w) in enumerate(agent.primitives) if v == 1.0 and w == 0.0)
    in_place = next(i for i, (v, w) in enumerate(agent.primitives) if v == 0.0)
    first = agent._plans[straight][2]
    assert 1.0 < first[-1, 0] < 2.5 - agent._safe and not agent._vetoed(first, pose, points, segments)
    assert agent._vetoed(to_world(first, first[-1]), pose, points, segments)
    assert not agent._vetoed(to_world(agent._plans[in_place][2], first[-1]), pose, points, segments)
