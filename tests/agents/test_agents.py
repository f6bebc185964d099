"""The agents: every one runs an episode with valid actions of the kind it declares; the greedy planner's pieces
do what they claim."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from ekfslam_gym.agents import (
    AGENTS,
    BASELINES,
    ActionKind,
    CircleAgent,
    GreedyInfoGainAgent,
    LawnmowerAgent,
    PPOAgent,
    make_agent,
    wall_scan,
)
from ekfslam_gym.agents.greedy import expected_readings, rollout_gain
from ekfslam_gym.agents.navigation import distance_field, update_walls
from ekfslam_gym.agents.planners import PLANNER_CLASSES, PLANNERS, make_planner
from ekfslam_gym.agents.ppo import model_paths, trained_action_kind

import ekfslam_gym  # noqa: F401  (registers the env ids)
from ekfslam_gym.filter.models import range_bearing
from tests.agent_runs import agent_actions


def _run(agent, seed=0, steps=50, env_id="EKFSLAM-v0"):
    return agent_actions(agent, seed, steps, env_id, tries=steps + 1)


@pytest.mark.parametrize("name", BASELINES)
def test_every_baseline_runs_an_episode_with_valid_actions(name):
    actions, truncated = _run(make_agent(name))
    assert truncated and len(actions) == 50
    for action in actions:
        assert isinstance(action, np.ndarray) and action.dtype == np.float32 and action.shape == (2,)
        assert np.all(np.isfinite(action)) and np.all(np.abs(action) <= 1.0)


def _is_of_kind(action, kind: ActionKind) -> bool:
    if kind is ActionKind.PRIMITIVES:
        return isinstance(action, np.int64)
    return isinstance(action, np.ndarray) and action.dtype == np.float32 and action.shape == (2,)


@pytest.mark.parametrize(
    ("name", "kind"), [(n, c.action_kind) for n, cs in PLANNER_CLASSES.items() for c in cs]
)
def test_every_planner_returns_actions_of_the_kind_it_declares(name, kind):
    env = gym.make("EKFSLAM-v0", action={"kind": str(kind), "hold": 10}, max_episode_steps=4)
    planner = make_planner(name, str(kind))
    assert planner.action_kind is kind and ActionKind.of_env(env) is kind
    observation, _ = env.reset(seed=3)
    planner.reset(env, seed=3)
    for _ in range(4):
        action = planner.act(observation)
        assert _is_of_kind(action, kind), (name, kind, action)
        assert env.action_space.contains(action)
        planner.executed(action)  # what a learner drove instead (DAgger): the planner only notes it
        observation, *_ = env.step(action)
    env.close()


def test_the_planners_interfaces_are_read_from_their_declarations():
    assert PLANNERS == {"greedy": ("primitives",), "frontier": ("waypoint", "primitives")}
    # every registered agent acts in velocity but the policy and the planners, named by their own interface
    planners = {cls.name: cls for classes in PLANNER_CLASSES.values() for cls in classes}
    assert {name: AGENTS[name] for name in planners} == planners
    assert all(str(cls.action_kind) == name.rpartition("-")[2] for name, cls in planners.items())
    assert all(
        cls.action_kind is ActionKind.VELOCITY
        for name, cls in AGENTS.items()
        if name not in {"ppo", *planners}
    )
    with pytest.raises(ValueError, match="demonstrates in action.kind primitives, not 'waypoint'"):
        make_planner("greedy", "waypoint")
    with pytest.raises(ValueError, match="unknown demonstration planner"):
        make_planner("lawnmower", "velocity")


def test_an_action_kind_makes_its_own_type_of_action():
    assert ActionKind("primitives") is ActionKind.PRIMITIVES and str(ActionKind.WAYPOINT) == "waypoint"
    index = ActionKind.PRIMITIVES.action(np.array([3]))
    assert isinstance(index, np.int64) and index == 3
    goal = ActionKind.WAYPOINT.action([0.5, -0.25])
    assert goal.dtype == np.float32 and goal.shape == (2,) and goal.tolist() == [0.5, -0.25]
    with pytest.raises(ValueError):
        ActionKind.VELOCITY.action([1.0, 2.0, 3.0])
    with pytest.raises(ValueError):
        ActionKind("teleport")
    # a saved policy's kind: a Discrete space is primitives; a Box is what its training env's settings say
    assert trained_action_kind(gym.spaces.Discrete(7), None) is ActionKind.PRIMITIVES
    box = gym.spaces.Box(-1.0, 1.0, (2,))
    assert trained_action_kind(box, {"action": {"kind": "waypoint", "hold": 10}}) is ActionKind.WAYPOINT
    assert trained_action_kind(box, {"max_episode_steps": 50}) is None


@pytest.mark.parametrize("name", ["lawnmower", "greedy"])
@pytest.mark.parametrize("env_id", ["EKFSLAM-Loop-v0", "EKFSLAM-Large-v0"])
def test_planners_run_in_the_other_layouts(name, env_id):
    actions, _ = _run(make_agent(name), seed=1, steps=30, env_id=env_id)
    assert np.all(np.abs(actions) <= 1.0)


def test_make_agent_knows_every_agent_and_rejects_others():
    planners = {cls.name for classes in PLANNER_CLASSES.values() for cls in classes}
    assert set(BASELINES) | {"ppo", "greedy2"} | planners == set(AGENTS)
    assert isinstance(make_agent("circle", radius=2.0), CircleAgent)
    with pytest.raises(ValueError, match="unknown agent"):
        make_agent("teleport")


def test_random_agent_is_seeded():
    first, _ = _run(make_agent("random"), seed=3, steps=10)
    second, _ = _run(make_agent("random"), seed=3, steps=10)
    other, _ = _run(make_agent("random"), seed=4, steps=10)
    assert np.array_equal(first, second) and not np.array_equal(first, other)


def test_circle_turns_at_the_rate_of_its_radius():
    env = gym.make("EKFSLAM-v0")
    env.reset(seed=0)
    agent = CircleAgent(radius=2.5, speed=0.8)
    agent.reset(env, seed=0)
    robot = env.unwrapped.config.robot
    v, omega = agent.act(None)
    assert v * robot.v_max / (omega * robot.omega_max) == pytest.approx(2.5, rel=1e-6)


def test_lawnmower_lanes_lie_inside_the_bounds_and_start_near_the_robot():
    env = gym.make("EKFSLAM-v0")
    env.reset(seed=5)
    agent = LawnmowerAgent(lane_spacing=5.0)
    agent.reset(env, seed=5)
    xmin, ymin, xmax, ymax = env.unwrapped.world.layout.bounds
    points = agent.waypoints
    assert np.all(
        (points[:, 0] > xmin) & (points[:, 0] < xmax) & (points[:, 1] > ymin) & (points[:, 1] < ymax)
    )
    assert len(points) == 8  # 4 lanes, 5 m apart, over 20 m
    corners = np.array([[x, y] for x in (points[:, 0].min(), points[:, 0].max()) for y in (points[:, 1].min(), points[:, 1].max())])  # fmt: skip
    start = np.asarray(env.unwrapped.filter.pose[:2])
    assert np.linalg.norm(points[0] - start) == pytest.approx(np.linalg.norm(corners - start, axis=1).min())


@pytest.mark.parametrize("kind", ["box", "dict"])
def test_wall_scan_reads_the_observation_in_metres(kind):
    env = gym.make("EKFSLAM-v0", observation={"kind": kind})
    observation, _ = env.reset(seed=4)
    for _ in range(5):
        observation, *_ = env.step(np.array([1.0, 0.3], dtype=np.float32))
    truth = np.minimum(env.unwrapped.world.scan(), env.unwrapped.config.sensor.scan_max_range)
    assert wall_scan(env.unwrapped, observation) == pytest.approx(truth, rel=1e-6)
    env.close()


@pytest.fixture
def greedy_mid_episode():
    """A greedy agent 30 steps into a seeded episode (so the filter has landmarks and correlations), with the
    turn-drive-turn odometry model, which the independent rollout below writes out."""
    env = gym.make("EKFSLAM-v0", filter={"motion_model": "odometry"})
    observation, _ = env.reset(seed=2)
    agent = GreedyInfoGainAgent()
    agent.reset(env, seed=2)
    for _ in range(30):
        observation, *_ = env.step(agent.act(observation))
    yield env, agent, observation
    env.close()


def test_greedy_expected_gain_matches_a_direct_filter_rollout(greedy_mid_episode):
    """The planner's number equals an independent rollout: predict with the arc's odometry and the alpha
    model's noise, then correct with h(predicted pose, estimated landmark) for every landmark in view."""
    env, agent, _ = greedy_mid_episode
    u = env.unwrapped
    cfg, ekf = u.config, u.filter
    alphas = cfg.odometry
    sensor = cfg.sensor
    checked = 0
    for index, (v_frac, w_frac) in enumerate(agent.primitives):
        v, w = v_frac * cfg.robot.v_max, w_frac * cfg.robot.omega_max
        rot = 0.5 * w * cfg.dt
        trans = v * cfg.dt * (math.sin(rot) / rot if rot else 1.0)
        std = [
            alphas.alpha1 * abs(rot) + alphas.alpha2 * abs(trans) + alphas.rot_floor,
            alphas.alpha3 * abs(trans) + alphas.alpha4 * 2 * abs(rot) + alphas.trans_floor,
            alphas.alpha1 * abs(rot) + alphas.alpha2 * abs(trans) + alphas.rot_floor,
        ]
        sim = ekf.copy()
        before = sim.log_det
        for _ in range(agent.horizon):
            sim.predict([rot, trans, rot], control_cov=np.diag(np.square(std)))
            ids, z = [], []
            for j in np.flatnonzero(sim.observed):
                reading, _, _ = range_bearing(np.array(sim.pose), np.array(sim.landmarks[j]), 1e-3)
                if (
                    max(sensor.min_range, 1e-3) <= reading[0] <= sensor.max_range
                    and abs(reading[1]) <= sensor.fov / 2
                ):
                    ids.append(j)
                    z.append(reading)
            if ids:
                sim.correct(np.array(ids), np.array(z))
                checked += 1
        assert agent.expected_gain(index) == pytest.approx(before - sim.log_det, rel=1e-9, abs=1e-9)
    assert checked > 0  # some rollout did see landmarks, so the corrections were compared too


def test_expected_readings_are_exact_for_landmarks_in_view():
    landmarks = np.array([[3.0, 0.0], [0.0, 2.0], [-2.0, 0.0], [10.0, 0.0]])
    ids, z = expected_readings(
        np.array([0.0, 0.0, 0.0]), landmarks, np.array([True, True, True, True]), 0.2, 6.0, math.pi
    )
    assert ids.tolist() == [0, 1]  # behind the robot and out of range are not read
    assert z[0] == pytest.approx([3.0, 0.0]) and z[1] == pytest.approx([2.0, math.pi / 2])


def test_rollout_gain_leaves_the_filter_alone(greedy_mid_episode):
    env, agent, _ = greedy_mid_episode
    ekf = env.unwrapped.filter
    mean, cov = np.array(ekf.mean), np.array(ekf.cov)
    controls, covs, _ = agent._plans[0]
    rollout_gain(ekf, controls, covs, 0.2, 6.0, math.pi)
    assert np.array_equal(mean, ekf.mean) and np.array_equal(cov, ekf.cov)


def test_greedy_vetoes_driving_into_a_scanned_wall_but_never_turning_in_place(greedy_mid_episode):
    env, agent, _ = greedy_mid_episode
    beams = agent._angles
    # A straight wall 0.5 m ahead of the robot, perpendicular to its heading, as the scan would see it.
    with np.errstate(divide="ignore"):
        scan = np.where(np.cos(beams) > 0.05, 0.5 / np.cos(beams), np.inf)
    scan = np.minimum(scan, env.unwrapped.config.sensor.scan_max_range)
    pose = np.array([10.0, 10.0, 0.0])  # mid-arena, so the bounds rule out nothing
    vetoed = agent.vetoed_primitives(scan, pose)
    straight = [i for i, (v, w) in enumerate(agent.primitives) if v > 0 and w == 0]
    in_place = [i for i, (v, w) in enumerate(agent.primitives) if v == 0]
    assert vetoed[straight].all() and not vetoed[in_place].any()
    open_scan = np.full_like(beams, env.unwrapped.config.sensor.scan_max_range)
    assert not agent.vetoed_primitives(open_scan, pose).any()


def test_frontier_distances_go_around_walls():
    """The frontier field is a shortest path through non-wall cells: around a wall, never through it or
    diagonally past its end."""
    wall = np.zeros((5, 5), dtype=bool)
    wall[0:4, 2] = True  # a wall across the grid with an opening in the top row
    start = np.full((5, 5), np.inf)
    start[0, 0] = 0.0
    d = distance_field(start, wall, 1.0, 64)
    assert d[0, 1] == pytest.approx(1.0) and d[1, 1] == pytest.approx(math.sqrt(2))
    # (0,0) -> (4,1): one diagonal and three steps; along row 4 past the wall's end: two steps (no corner
    # cutting); (4,3) -> (0,4): one diagonal and three steps.
    assert d[0, 4] == pytest.approx(8 + 2 * math.sqrt(2))
    assert np.all(np.isinf(d[wall]))


def test_wall_memory_marks_scan_ends_and_reopens_what_a_beam_crosses():
    wall = np.zeros((20, 20), dtype=bool)  # 0.5 m cells over 10 m x 10 m
    angles = np.arange(16) * (2 * math.pi / 16)
    scan = np.full(16, 5.0)
    scan[0] = 2.0  # a surface 2 m ahead of a robot at (5, 5) facing +x
    update_walls(wall, 0.0, 0.0, 0.5, 5.0, 5.0, 0.0, angles, scan, 5.0 - 1e-6, 1.5)
    assert wall[10, 14] and wall.sum() == 1
    scan[0] = 5.0  # later the same beam passes: the cell is free after all (an opened doorway)
    update_walls(wall, 0.0, 0.0, 0.5, 5.0, 5.0, 0.0, angles, scan, 5.0 - 1e-6, 1.5)
    assert not wall.any()


@pytest.mark.parametrize("env_id", ["EKFSLAM-Loop-v0", "EKFSLAM-Large-v0"])
def test_greedy_leaves_its_start_in_walled_layouts(env_id):
    """Not a quality claim: a straight-line pull towards unexplored space behind a wall once kept it pinned
    there; the path-based frontier term must let it travel."""
    env = gym.make(env_id, max_episode_steps=150)
    observation, info = env.reset(seed=0)
    start = np.array(info["true_pose"][:2])
    agent = GreedyInfoGainAgent()
    agent.reset(env, seed=0)
    farthest = 0.0
    while True:
        observation, _, terminated, truncated, info = env.step(agent.act(observation))
        farthest = max(farthest, float(np.linalg.norm(info["true_pose"][:2] - start)))
        if terminated or truncated:
            break
    assert farthest > 4.0
    env.close()


def test_greedy_explores_rather_than_sitting_still():
    """Not a quality claim: the exploration terms make it move (a pure D-opt planner may spin in place)."""
    env = gym.make("EKFSLAM-v0", max_episode_steps=60)
    observation, info = env.reset(seed=0)
    agent = GreedyInfoGainAgent()
    agent.reset(env, seed=0)
    while True:
        observation, _, terminated, truncated, info = env.step(agent.act(observation))
        if terminated or truncated:
            break
    assert info["path_length"] > 1.0
    env.close()


# ---------------------------------------------------------------------------------------------------- PPO
@pytest.fixture(scope="module")
def tiny_ppo(tmp_path_factory):
    """A PPO trained for 64 steps on short episodes, saved with VecNormalize statistics by the convention."""
    pytest.importorskip("stable_baselines3")
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    torch.set_num_threads(1)
    venv = VecNormalize(make_vec_env("EKFSLAM-v0", n_envs=1, seed=0, env_kwargs={"max_episode_steps": 32}))
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=32, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=64)
    path = tmp_path_factory.mktemp("ppo") / "tiny"
    zip_path, stats_path = model_paths(path)
    model.save(zip_path)
    venv.save(stats_path)
    (zip_path.parent / "config.yaml").write_text(
        "env_id: EKFSLAM-v0\nentry:\n  env_kwargs: {}\n"
    )  # as train.py
    venv.close()
    return zip_path


def test_ppo_agent_loads_the_model_and_its_normalisation(tiny_ppo):
    agent = make_agent("ppo", model_path=tiny_ppo)
    assert agent.vecnormalize is not None and not agent.vecnormalize.training
    actions, truncated = _run(agent, steps=20)
    assert truncated and actions.dtype == np.float32 and np.all(np.abs(actions) <= 1.0)
    # deterministic, and on normalised observations: the model's own mean action on the normalised input
    env = gym.make("EKFSLAM-v0")
    observation, _ = env.reset(seed=0)
    agent.reset(env, seed=0)
    expected, _ = agent.model.predict(agent.vecnormalize.normalize_obs(observation), deterministic=True)
    assert np.allclose(agent.act(observation), np.clip(expected, -1, 1))
    assert np.array_equal(agent.act(observation), agent.act(observation))
    env.close()


def test_ppo_agent_path_without_zip_and_clear_errors(tiny_ppo, tmp_path):
    assert PPOAgent(str(tiny_ppo.with_suffix(""))).model_path == tiny_ppo
    with pytest.raises(FileNotFoundError, match="no saved model"):
        PPOAgent(tmp_path / "missing.zip")
    with pytest.raises(ValueError, match="model_path"):
        PPOAgent()
    agent = PPOAgent(tiny_ppo)
    env = gym.make("EKFSLAM-v0", observation={"grid": 4})  # a different observation size
    env.reset(seed=0)
    with pytest.raises(ValueError, match="trained on observations"):
        agent.reset(env, seed=0)
    env.close()


def test_evaluate_cli_runs_the_ppo_agent(tiny_ppo, capsys):
    import json

    from ekfslam_gym.cli.evaluate import main

    argv = ["--agent", "ppo", "--model", str(tiny_ppo), "--seeds", "0-1", "--max-episode-steps", "10"]
    assert main([*argv, "--json", "--no-progress"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["agent"] == "ppo" and result["episodes"] == 2
    # two models (the same one twice here) are pooled into one row unless --per-model
    assert main([*argv, "--model", str(tiny_ppo), "--json", "--no-progress"]) == 0
    assert json.loads(capsys.readouterr().out)["episodes"] == 4
    # trained on the default config: evaluating it on another warns (on stderr; stdout stays one JSON object)
    other = ["--env-kwargs", '{"reward": {"collision": 2.0}}']
    assert main([*argv, *other, "--json", "--no-progress"]) == 0
    captured = capsys.readouterr()
    assert "trained with env_kwargs" in captured.err and json.loads(captured.out)["agent"] == "ppo"


def test_per_model_rows_are_named_by_run_when_files_share_a_name(tiny_ppo, tmp_path, capsys):
    """Every run's best_model.zip: --per-model must give one row per run, not overwrite one label."""
    import json
    import shutil

    from ekfslam_gym.cli.evaluate import main

    models = []
    for run in ("run_a", "run_b"):
        folder = tmp_path / run
        folder.mkdir()
        for source in tiny_ppo.parent.iterdir():
            name = source.name.replace(tiny_ppo.stem, "best_model")
            shutil.copy(source, folder / name)
        models += ["--model", str(folder / "best_model.zip")]
    argv = ["--agent", "ppo", *models, "--per-model", "--seeds", "0", "--max-episode-steps", "5", "--json"]
    assert main([*argv, "--no-progress"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert list(rows) == ["ppo[run_a/best_model]", "ppo[run_b/best_model]"]
