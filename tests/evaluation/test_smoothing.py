"""Filter vs full-SLAM smoother on recorded env episodes."""

import gymnasium as gym
import numpy as np
import pytest
from ekfslam_gym.agents import make_agent

import ekfslam_gym  # noqa: F401
from ekfslam_gym.cli.smoothing import main
from ekfslam_gym.evaluation.rollout import run_episode
from ekfslam_gym.evaluation.smoothing import EpisodeRecorder, compare_with_smoother


@pytest.mark.parametrize("seed", [10000, 10001])
def test_smoothing_an_env_episode_beats_the_filter_on_ate(seed):
    env = gym.make("EKFSLAM-v0")  # 500 steps: the circle closes its loop
    recorder = EpisodeRecorder()
    run_episode(env, make_agent("circle"), seed, recording=recorder)
    assert len(recorder.odometry) == 500 and len(recorder.readings) == 501
    result = compare_with_smoother(recorder, env)
    assert result["smoother_ate"] < 0.7 * result["filter_ate"], result
    assert result["smoother_landmark_rmse"] < 0.2


def test_recorder_keeps_what_the_graph_needs():
    env = gym.make("EKFSLAM-v0", max_episode_steps=5)
    _, info = env.reset(seed=3)
    recorder = EpisodeRecorder()
    recorder.add(info, first=True)
    _, _, _, _, info = env.step(np.array([0.5, 0.1], dtype=np.float32))
    recorder.add(info)
    assert recorder.readings[0].shape[1] == 3 and len(recorder.odometry) == 1
    np.testing.assert_array_equal(recorder.readings[1][:, 0], info["readings"].ids)
    velocity = gym.make("EKFSLAM-v0", filter={"motion_model": "velocity"})
    _, info = velocity.reset(seed=0)
    _, _, _, _, info = velocity.step(np.zeros(2, dtype=np.float32))
    with pytest.raises(ValueError, match="reads odometry or wheels odometry, not velocity"):
        recorder.add(info)


def test_the_recorder_takes_wheel_odometry_too():
    env = gym.make("EKFSLAM-v0", filter={"motion_model": "wheels"}, max_episode_steps=30)
    recorder = EpisodeRecorder()
    run_episode(env, make_agent("circle"), 3, recording=recorder)
    assert len(recorder.odometry) == 30
    assert compare_with_smoother(recorder, env)["steps"] == 30


def test_cli_prints_a_row_per_seed(capsys):
    assert main(["--seeds", "10000-10000", "--json"]) == 0
    import json

    rows = json.loads(capsys.readouterr().out)
    assert len(rows) == 1 and {"filter_ate", "smoother_ate"} <= set(rows[0])
