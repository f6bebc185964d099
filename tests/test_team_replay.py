"""Cooperative SLAM on MRCLAM (``evaluation.team_replay``): cutting a drive's steps is exact, the joint replay
of an excerpt of the five robots runs with its bookkeeping exact, and the command line's ``--team`` checks."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ekfslam_gym.data.mrclam import ROBOT_SUBJECTS, load_mrclam
from ekfslam_gym.evaluation.mrclam import Drive, ReplaySettings
from ekfslam_gym.evaluation.team_replay import TeamReplaySettings, replay_team, split_drive
from ekfslam_gym.filter import EKFSLAM
from tests.datapaths import mrclam_dir


def _five_robots():
    folder = mrclam_dir()
    if folder is None or not all((folder / f"Robot{k}_Odometry.dat").is_file() for k in ROBOT_SUBJECTS):
        pytest.skip(
            "MRCLAM data set 1 with robots 1-5 not found: ../shared/data/mrclam (or EKFSLAM_MRCLAM_DIR)"
        )
    return folder, [load_mrclam(folder, robot) for robot in ROBOT_SUBJECTS]


def _poses_at(drive: Drive, times: np.ndarray) -> np.ndarray:
    """Dead reckoning of ``drive`` with the velocity model on its increments: the pose at each of ``times``."""
    ekf = EKFSLAM(0, motion_model="velocity", dt=1.0)
    out = {}
    for k in range(len(drive)):
        ekf.predict(drive.increments[k], control_cov=np.eye(2) * 1e-6)
        out[round(float(drive.time[k + 1]), 9)] = ekf.pose.copy()
    return np.array([out[round(float(t), 9)] for t in times])


def test_cutting_steps_keeps_the_path_and_the_readings():
    rng = np.random.default_rng(0)
    time = np.cumsum(np.r_[10.0, rng.uniform(0.05, 0.5, 40)])
    increments = np.column_stack([rng.uniform(0, 0.1, 40), rng.normal(0, 0.2, 40)])
    counts = rng.integers(0, 3, 40)
    offsets = np.r_[0, np.cumsum(counts)]
    z = rng.uniform(1, 2, (offsets[-1], 2))
    drive = Drive(time, increments, offsets, z, rng.integers(1, 20, offsets[-1]))
    cuts = np.sort(rng.uniform(time[0] - 1, time[-1] + 1, 25))
    split = split_drive(drive, cuts)
    inside = cuts[(cuts > time[0]) & (cuts < time[-1])]
    assert len(split) == len(np.union1d(time, inside)) - 1
    np.testing.assert_allclose(split.increments.sum(axis=0), increments.sum(axis=0), atol=1e-12)
    # every reading keeps its time and its row
    for k in range(len(drive)):
        rows = drive.readings(k)
        if rows.stop > rows.start:
            j = int(np.searchsorted(split.time, time[k + 1])) - 1
            assert split.time[j + 1] == time[k + 1] and split.readings(j) == rows
    # arcs of one held command compose exactly: the path through the old step ends is unchanged
    np.testing.assert_allclose(_poses_at(split, time[1:]), _poses_at(drive, time[1:]), atol=1e-12)


def test_five_robots_on_an_excerpt():
    _, runs = _five_robots()
    result = replay_team(runs, TeamReplaySettings(seconds=40.0))
    team = result.team
    assert team.n_robots == 5 and team.state_size == 15 + 2 * 15
    assert len(result.robot_nis) > 0 and len(result.landmark_nis) > 0
    assert np.all(np.isfinite(result.robot_nis)) and np.all(result.robot_nis >= 0)
    assert set(result.robot_observer.tolist()) <= set(range(5))
    assert np.all(result.robot_observer != result.robot_target)
    sign, log_det = np.linalg.slogdet(team.cov)
    assert sign > 0 and abs(team.log_det - log_det) <= 1e-6 * max(1.0, abs(log_det))
    errors, _ = result.landmark_errors()
    assert len(errors) == int(team.observed.sum()) >= 2
    np.testing.assert_array_equal(result.starts[0], 0.0)
    for path, drive in zip(result.paths, result.drives, strict=True):
        assert path.shape == (len(drive) + 1, 3) and np.all(np.isfinite(path))
    # the same excerpt without the robot readings fuses none
    alone = replay_team(runs, TeamReplaySettings(seconds=40.0, robot_readings=False))
    assert len(alone.robot_nis) == 0 and len(alone.landmark_nis) > 0


def test_team_settings_refuse_bad_values():
    with pytest.raises(ValueError, match="association must be 'known'"):
        TeamReplaySettings(replay=ReplaySettings(association="jcbc"))
    with pytest.raises(ValueError, match="start_std"):
        TeamReplaySettings(start_std=(0.1, 0.0, 0.1))
    with pytest.raises(ValueError, match="robot_range_std"):
        TeamReplaySettings(robot_range_std=-1.0)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--team", "--smoother"], "--team reads the barcodes"),
        (["--team", "--association", "jcbc"], "--team reads the barcodes"),
        (["--team", "--robots"], "--team reads the barcodes"),
    ],
)
def test_team_option_refuses_what_does_not_apply(tmp_path, capsys, argv, message):
    from ekfslam_gym.cli.replay import main

    (tmp_path / "Barcodes.dat").write_text("1 5\n")
    with pytest.raises(SystemExit) as raised:
        main(["--data", str(tmp_path), *argv])
    assert raised.value.code == 2 and message in capsys.readouterr().err


@pytest.mark.slow
def test_team_command_reports_the_five_robots_and_the_team(capsys):
    from ekfslam_gym.cli.replay import main

    folder, _ = _five_robots()
    assert main(["--data", str(folder), "--team", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert [s["robot"] for s in figures["single"]] == list(ROBOT_SUBJECTS)
    team = figures["team"]
    assert team["landmarks_mapped"] == 15 and team["robot_nis"]["readings"] > 1000
    assert team["within_0.18"] >= 12  # the swapped pair of landmarks aside (the data's barcodes)
