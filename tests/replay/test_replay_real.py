"""The replay package on real data: one result type, one smoother comparison, one report for every data set, the
format detection, the settings built on FilterSettings, and the command line that only parses and prints."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from ekfslam_gym.data.gtsam2d import read_gtsam2d
from ekfslam_gym.data.mrclam import load_mrclam
from ekfslam_gym.data.synthetic import simulate_drive
from ekfslam_gym.evaluation.report import json_safe
from ekfslam_gym.filter import AssociationSettings, FilterSettings
from ekfslam_gym.replay import real
from ekfslam_gym.replay.chain import replay_chain
from ekfslam_gym.replay.course import replay
from ekfslam_gym.replay.formats import detect_dataset
from ekfslam_gym.replay.mrclam import FITTED_MRCLAM, ReplaySettings, build_drive, replay_drive
from ekfslam_gym.replay.result import Replay
from ekfslam_gym.replay.smoother import compare_with_smoother, trajectory_gap
from tests.replay.test_mrclam import _folder

STEPS = [(1.0, 0.2, 0.3), (0.5, -0.1, -0.8), (0.0, 0.0, 0.4), (2.0, 0.0, 0.0)]
READINGS = [
    "LANDMARK 1 0 5.0 1.0 0.4 0 0.4",
    "LANDMARK 3 0 3.6 -1.2 0.4 0 0.4",
    "LANDMARK 4 0 2.9 -0.4 0.4 0 0.4",
]


def _chain(tmp_path, readings=READINGS):
    lines = [
        f"ODOMETRY {i} {i + 1} {dx} {dy} {dt} 0.0001 0 0 4e-06 0 4e-06"
        for i, (dx, dy, dt) in enumerate(STEPS)
    ]
    path = tmp_path / "chain.txt"
    path.write_text("\n".join(lines + list(readings)) + "\n")
    return path


def test_every_replay_returns_the_one_result_type(tmp_path):
    drive = simulate_drive(0)
    course = replay(drive.data, world=drive.world, steps=20)
    chain = replay_chain(read_gtsam2d(_chain(tmp_path)))
    folder = tmp_path / "mrclam"
    folder.mkdir()
    run = load_mrclam(_folder(folder))
    mrclam = replay_drive(build_drive(run), run.landmarks.ids)
    for result, steps in ((course, 20), (chain, len(STEPS)), (mrclam, len(build_drive(run)))):
        assert type(result) is Replay and result.steps == steps and result.poses.shape == (steps + 1, 3)
        np.testing.assert_array_equal(result.poses[-1], result.ekf.pose)
    assert set(mrclam.landmark_estimates()) == {6, 7} and len(chain.nis) == len(chain.nis_at) == 2


def test_the_smoother_agrees_with_the_filter_on_pure_odometry(tmp_path):
    """No reading: the smoother's optimum is the odometry's composition, which the filter follows exactly."""
    dataset = read_gtsam2d(_chain(tmp_path, readings=[]))
    result = replay_chain(dataset)
    comparison = compare_with_smoother(result, dataset)
    assert comparison.gap_rms < 1e-6 and comparison.gap_max < 1e-6
    assert set(comparison.figures()) == {
        "chi2",
        "iterations",
        "seconds",
        "trajectory_gap_rms",
        "trajectory_gap_max",
    }


def test_the_trajectory_gap_is_the_distance_pose_by_pose():
    a = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.5], [2.0, 0.0, 1.0]])
    b = a + np.array([[3.0, 4.0, 9.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert trajectory_gap(a, b) == pytest.approx((np.sqrt(25.0 / 3.0), 5.0))


def test_one_report_for_every_data_set(tmp_path):
    chain = real.replay_gtsam(read_gtsam2d(_chain(tmp_path)), "fej", smoother=True)
    text = real.text_report(chain.figures, "chain.txt")
    assert text.startswith("EKF-SLAM (fej) on chain.txt: 4 steps") and "NIS: mean" in text
    assert "smoother (LM): chi2" in text and "landmarks after SE(2)" not in text
    folder = tmp_path / "mrclam"
    folder.mkdir()
    run = load_mrclam(_folder(folder))
    surveyed = real.replay_mrclam(run, FITTED_MRCLAM.choosing(association="nearest"))
    text = real.text_report(surveyed.figures, folder)
    assert "EKF-SLAM (ekf, nearest association)" in text and "landmarks after SE(2) alignment" in text
    assert "associations against the barcodes" in text and "smoother" not in text
    with_smoother = real.replay_mrclam(run, smoother=True).figures["smoother"]
    assert {"chi2", "dof", "trajectory_gap_rms", "landmark_errors", "median_error"} <= set(with_smoother)


def test_pictures_of_both_data_sets(tmp_path):
    pytest.importorskip("matplotlib")
    chain = real.replay_gtsam(read_gtsam2d(_chain(tmp_path)), smoother=True)
    folder = tmp_path / "mrclam"
    folder.mkdir()
    surveyed = real.replay_mrclam(load_mrclam(_folder(folder)), smoother=True)
    for name, run in (("chain.png", chain), ("mrclam.png", surveyed)):
        path = run.save_picture(tmp_path / name)
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_format_is_detected(tmp_path):
    assert detect_dataset(None) == "course"
    assert detect_dataset(_chain(tmp_path)) == "gtsam"
    course = tmp_path / "sensor_data.dat"
    course.write_text("ODOMETRY 0.1 0.2 0.0\nSENSOR 1 2.0 0.1\n")
    assert detect_dataset(course) == "course"
    folder = tmp_path / "mrclam"
    folder.mkdir()
    assert detect_dataset(_folder(folder)) == "mrclam"


def test_replay_settings_are_built_on_the_filter_settings():
    settings = ReplaySettings()
    assert settings.filter == FilterSettings(motion_model="velocity", init_mode="inverse")
    assert settings.association == AssociationSettings()
    chosen = FITTED_MRCLAM.choosing(variant="iekf", association="jcbc")
    assert (chosen.filter.variant, chosen.association.kind) == ("iekf", "jcbc")
    assert chosen.range_std == FITTED_MRCLAM.range_std and chosen.association.gate_prob == 0.99
    assert FITTED_MRCLAM.choosing() == FITTED_MRCLAM
    with pytest.raises(ValueError, match="velocity model"):
        ReplaySettings(filter=FilterSettings(motion_model="odometry"))
    with pytest.raises(ValueError, match="range_std must be > 0"):
        dataclasses.replace(settings, range_std=0.0)
    with pytest.raises(ValueError, match="association.kind"):
        settings.choosing(association="magic")


def test_the_command_line_reports_a_broken_file_as_usage_and_a_deep_error_as_a_bug(
    tmp_path, capsys, monkeypatch
):
    from ekfslam_gym.cli.replay import main

    broken = tmp_path / "broken.txt"
    broken.write_text("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 x 0\n")
    with pytest.raises(SystemExit) as info:
        main(["--data", str(broken), "--dataset", "gtsam"])
    assert info.value.code == 2 and f"{broken}:2:" in capsys.readouterr().err
    unordered = tmp_path / "unordered.txt"
    unordered.write_text("ODOMETRY 1 2 1 0 0 1 0 0 1 0 1\nODOMETRY 0 1 1 0 0 1 0 0 1 0 1\n")
    with pytest.raises(SystemExit) as info:
        main(["--data", str(unordered)])
    assert info.value.code == 2 and "odometry chain" in capsys.readouterr().err

    def broken_filter(*args, **kwargs):
        raise ValueError("a bug deep in the filter")

    monkeypatch.setattr(real, "replay_gtsam", broken_filter)
    with pytest.raises(ValueError, match="a bug deep in the filter"):
        main(["--data", str(_chain(tmp_path))])


def test_the_command_line_prints_the_library_figures(tmp_path, capsys):
    from ekfslam_gym.cli.replay import main

    path = _chain(tmp_path)
    assert main(["--data", str(path), "--json", "--smoother"]) == 0
    printed = json.loads(capsys.readouterr().out)
    figures = json_safe(real.replay_gtsam(read_gtsam2d(path), smoother=True).figures)
    for key in ("variant", "steps", "landmarks_mapped", "nis"):
        assert printed[key] == figures[key]
    assert printed["smoother"]["chi2"] == pytest.approx(figures["smoother"]["chi2"])
