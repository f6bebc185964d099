"""Action interfaces (``action.kind``): macro steps are their control steps summed exactly, the waypoint
controller reaches free goals and stops short of walls, every kind passes the checkers and is deterministic."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401  (registers the envs)
from ekfslam_gym.envs import PRIMITIVES, EKFSLAMEnv
from ekfslam_gym.envs.actions import MotionPrimitives

KINDS = [
    {"kind": "velocity", "hold": 5},
    {"kind": "primitives"},
    {"kind": "primitives", "hold": 3},
    {"kind": "primitives", "guard": 0.2},
    {"kind": "waypoint"},
]


# Every optional reward term on.
SHAPED = {"step_cost": 0.05, "pose_variance": 7.0, "coverage": 1.0}


def _actions(env: gym.Env, n: int, seed: int) -> list:
    env.action_space.seed(seed)
    return [env.action_space.sample() for _ in range(n)]


@pytest.mark.parametrize("action", KINDS, ids=lambda a: f"{a['kind']}-{a.get('hold')}-{a.get('guard', 0)}")
def test_every_kind_passes_gymnasiums_checker(action):
    from gymnasium.utils.env_checker import check_env

    check_env(gym.make("EKFSLAM-v0", action=action, max_episode_steps=30).unwrapped, skip_render_check=True)


@pytest.mark.parametrize("action", KINDS, ids=lambda a: f"{a['kind']}-{a.get('hold')}-{a.get('guard', 0)}")
def test_every_kind_passes_sb3s_checker(action):
    env_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    env_checker.check_env(EKFSLAMEnv(action=action, max_episode_steps=30), warn=True)


@pytest.mark.parametrize("action", KINDS, ids=lambda a: f"{a['kind']}-{a.get('hold')}-{a.get('guard', 0)}")
@pytest.mark.parametrize("reward", [{}, SHAPED], ids=["default", "shaped"])
def test_a_macro_step_is_its_control_steps_summed_exactly(action, reward):
    """Replaying each macro step's inner actions one control step at a time gives the same filter state, and
    the macro reward is exactly the sum of those steps' rewards; each term, and the truth and belief gains, is the
    sum of its inner ones (with the default reward, and with every optional term switched on)."""
    macro = EKFSLAMEnv(action=action, max_episode_steps=40, reward=reward)
    single = EKFSLAMEnv(max_episode_steps=10_000, reward=reward)
    macro.reset(seed=7)
    single.reset(seed=7)
    for a in _actions(macro, 40, seed=1):
        _, reward, terminated, truncated, info = macro.step(a)
        inner = info["inner_actions"]
        assert inner.shape == (info["inner_steps"], 2) and 1 <= len(inner) <= macro.config.action.steps
        total, truth, belief, terms = 0.0, 0.0, 0.0, {}
        for command in inner:
            _, r, *_, single_info = single.step(command.astype(np.float64))
            total += r
            truth += single_info["truth_gain"]
            belief += single_info["belief_gain"]
            for name, value in single_info["reward_terms"].items():
                terms[name] = terms.get(name, 0.0) + value
        assert reward == total
        assert info["reward_terms"] == terms
        assert info["truth_gain"] == truth
        assert info["belief_gain"] == belief
        assert np.array_equal(macro.filter.mean, single.filter.mean)
        assert np.array_equal(macro.filter.cov, single.filter.cov)
        assert info["step"] == single_info["step"]
        if terminated or truncated:
            break


def test_information_gain_telescopes_over_macro_steps():
    env = EKFSLAMEnv(action={"kind": "primitives"}, max_episode_steps=20)
    _, info = env.reset(seed=3)
    start, gains = info["log_det"], 0.0
    for a in _actions(env, 20, seed=2):
        _, _, terminated, truncated, info = env.step(a)
        gains += info["reward_terms"]["info_gain"]
        if terminated or truncated:
            break
    assert gains == pytest.approx(start - info["log_det"], rel=1e-9, abs=1e-6)
    assert truncated  # the limit counts env steps: 20 macro steps of 10 control steps
    assert info["step"] == 200


@pytest.mark.parametrize("action", KINDS, ids=lambda a: f"{a['kind']}-{a.get('hold')}-{a.get('guard', 0)}")
def test_rollouts_are_deterministic(action):
    def rollout():
        env = gym.make("EKFSLAM-v0", action=action, max_episode_steps=25)
        obs, _ = env.reset(seed=11)
        out = [obs]
        for a in _actions(env, 25, seed=5):
            obs, reward, *_ = env.step(a)
            out += [obs, np.array([reward])]
        return np.concatenate([np.ravel(x) for x in out])

    assert np.array_equal(rollout(), rollout())


def test_primitives_are_the_greedy_planners_and_bad_indices_are_refused():
    from ekfslam_gym.agents.greedy import DEFAULT_PRIMITIVES

    assert tuple(DEFAULT_PRIMITIVES) == PRIMITIVES
    env = EKFSLAMEnv(action={"kind": "primitives"})
    assert env.action_space == gym.spaces.Discrete(len(PRIMITIVES))
    env.reset(seed=0)
    pose = env.world.pose
    for bad in (len(PRIMITIVES), -1, 1.5, np.array([0, 1])):
        with pytest.raises(ValueError, match="primitives action"):
            env.step(bad)
    assert np.array_equal(env.world.pose, pose) and env.elapsed_steps == 0  # nothing changed
    env.step(np.int64(0))
    assert env.elapsed_steps == 10


def test_bad_action_configs_name_the_field():
    with pytest.raises(ValueError, match="action.kind"):
        EKFSLAMEnv(action={"kind": "teleport"})
    with pytest.raises(ValueError, match="action.hold"):
        EKFSLAMEnv(action={"kind": "primitives", "hold": 0})
    with pytest.raises(ValueError, match="action.waypoint_radius"):
        EKFSLAMEnv(action={"kind": "waypoint", "waypoint_radius": -1.0})
    for bad in (-0.1, float("nan"), "0.2"):
        with pytest.raises(ValueError, match="action.guard"):
            EKFSLAMEnv(action={"kind": "primitives", "guard": bad})
    for kind in ("velocity", "waypoint"):
        with pytest.raises(ValueError, match="action.guard applies to action.kind primitives only"):
            EKFSLAMEnv(action={"kind": kind, "guard": 0.2})


def _open_arena(kind="waypoint", **action):
    """An arena with the start pose far from every wall (the layout's start is random)."""
    env = EKFSLAMEnv(action={"kind": kind, **action}, world={"layout": "arena"}, max_episode_steps=200)
    for seed in range(50):
        env.reset(seed=seed)
        x, y, _ = env.world.pose
        xmin, ymin, xmax, ymax = env.bounds
        if min(x - xmin, xmax - x, y - ymin, ymax - y) > 5.0:
            return env
    raise AssertionError("no start pose 5 m from the walls")


def test_a_waypoint_in_free_space_is_reached():
    env = _open_arena(hold=60)
    start = env.filter.pose.copy()
    _, _, _, _, info = env.step(np.array([1.0, 0.5], dtype=np.float32))  # 3 m ahead, 1.5 m to the left
    goal = start[:2] + np.array(
        [[math.cos(start[2]), -math.sin(start[2])], [math.sin(start[2]), math.cos(start[2])]]
    ) @ np.array([3.0, 1.5])
    assert info["inner_steps"] < 60  # it stopped because it got there
    assert np.linalg.norm(env.filter.pose[:2] - goal) <= env.unwrapped._interface.controller.tolerance + 1e-9
    assert not info["collision"]


def test_a_waypoint_behind_a_wall_stops_short_of_it():
    env = _open_arena(hold=200, waypoint_radius=30.0)
    x, y, theta = env.world.pose
    xmin, ymin, xmax, ymax = env.bounds
    # Face east first (turn in place with a waypoint just to the side), then aim 30 m east: beyond the wall.
    heading_east = -theta
    forward, left = math.cos(heading_east), math.sin(heading_east)
    collisions = 0
    for _ in range(6):
        _, _, _, _, info = env.step(np.array([forward, left], dtype=np.float32))
        collisions += info["collision"]
        x, y, theta = env.world.pose
        heading_east = -theta
        forward, left = math.cos(heading_east), math.sin(heading_east)
    assert collisions == 0
    assert xmax - x < 1.5  # it drove up to the wall ...
    assert xmax - x > env.config.robot.radius  # ... and stopped short of it


def _gap_to_walls(env) -> float:
    """m between the robot's disc and the nearest of the arena's four walls (the world's bounds)."""
    x, y, _ = env.world.pose
    xmin, ymin, xmax, ymax = env.bounds
    return min(x - xmin, xmax - x, y - ymin, ymax - y) - env.config.robot.radius


@pytest.mark.parametrize("guard", [0.1, 0.3])
def test_a_guarded_primitive_stops_short_of_the_wall_ahead(guard):
    """Driving straight on from a start 5 m from every wall: unguarded the robot runs into a wall and scrapes
    it; guarded it stops about ``guard`` short of it, turning without driving, and never touches it."""
    unguarded = _open_arena("primitives")
    contacts = sum(unguarded.step(np.int64(0))[4]["collision"] for _ in range(60))
    assert contacts > 0

    env = _open_arena("primitives", guard=guard)
    start = env.world.pose.copy()
    contacts, infos = 0, []
    for _ in range(60):
        infos.append(env.step(np.int64(0))[4])
        contacts += infos[-1]["collision"]
    assert contacts == 0
    assert np.linalg.norm(env.world.pose[:2] - start[:2]) > 3.0  # it drove to the wall ...
    step = env.config.robot.v_max * env.config.dt
    assert 0.5 * guard < _gap_to_walls(env) < guard + 2 * step  # ... and stopped short of it
    assert np.all(infos[-1]["inner_actions"] == 0.0)  # a straight primitive that is blocked stands still
    info = env.step(np.int64(3))[4]  # a blocked arc keeps its turn, and drives on once it has turned clear
    assert tuple(info["inner_actions"][0]) == (0.0, np.float32(PRIMITIVES[3][1])) and not info["collision"]


def test_a_guarded_primitive_backs_off_a_wall_it_is_already_against():
    """A robot the guard finds within ``guard`` of a wall ahead (the scan can miss a wall's end between its
    beams until the robot is upon it) backs off, turn kept, instead of standing against the wall; a straight
    primitive then stands at the guard, out of contact."""
    guard = 0.3
    env = _open_arena("primitives", guard=guard)
    guarded = env.unwrapped._interface
    env.unwrapped._interface = MotionPrimitives()  # unguarded: drive straight into the wall
    for _ in range(30):
        if env.step(np.int64(0))[4]["collision"]:
            break
    assert _gap_to_walls(env) < 0.05
    env.unwrapped._interface = guarded
    info = env.step(np.int64(3))[4]  # an arc: backs off while turning
    backoff = guarded.controller.backoff
    assert tuple(info["inner_actions"][0]) == (-backoff, np.float32(PRIMITIVES[3][1]))
    assert np.all(info["inner_actions"][:, 1] == np.float32(PRIMITIVES[3][1]))
    for _ in range(3):
        info = env.step(np.int64(0))[4]
    assert not info["collision"] and np.all(info["inner_actions"] == 0.0)  # standing clear of the wall
    step = env.config.robot.v_max * env.config.dt
    assert 0.5 * guard < _gap_to_walls(env) < guard + 2 * step


def test_the_guards_skip_bound_changes_no_decision():
    """The guard skips the room-ahead check when the scan's nearest wall is too far to matter; checking at every
    forward step instead drives the same commands, step for step, near walls and away from them."""
    for seed in range(3):
        envs = [
            EKFSLAMEnv(action={"kind": "primitives", "guard": 0.3}, max_episode_steps=150) for _ in range(2)
        ]
        envs[1]._interface._far = math.inf  # always measure the room ahead
        for env in envs:
            env.reset(seed=seed)
        blocked = 0
        for a in _actions(envs[0], 150, seed=seed):
            outs = [env.step(a) for env in envs]
            inner = [out[4]["inner_actions"] for out in outs]
            assert np.array_equal(inner[0], inner[1])
            if PRIMITIVES[int(a)][0] > 0.0:  # a forward primitive that the guard stopped for some steps
                blocked += int(np.sum(inner[0][:, 0] == 0.0))
            if outs[0][2] or outs[0][3]:
                break
        assert blocked > 0  # the drive came near walls, so the check was exercised
