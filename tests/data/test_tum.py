"""TUM trajectory export for evo: the file format (``ekfslam_gym.data.tum``), ``evaluate --export-tum`` and
``replay --tum``, and evo's own reader and APE on the files against the project's ATE."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from ekfslam_gym.agents import make_agent
from scipy.spatial.transform import Rotation

from ekfslam_gym.angles import wrap_angles
from ekfslam_gym.cli.evaluate import main as evaluate_main
from ekfslam_gym.cli.replay import main as replay_main
from ekfslam_gym.data.synthetic import simulate_drive
from ekfslam_gym.data.tum import LANDMARK_COLUMNS, read_tum, write_landmarks_csv, write_tum, yaw_quaternions
from ekfslam_gym.evaluation import metrics
from ekfslam_gym.evaluation.export import export_tum
from ekfslam_gym.evaluation.rollout import make_env, run_episode

# ------------------------------------------------------------------------------------------ the file format


def test_yaw_quaternions_are_rotations_about_z():
    theta = np.linspace(-3.0, 3.0, 13)
    expected = Rotation.from_euler("z", theta[:, None]).as_quat()  # scipy's order is TUM's: (x, y, z, w)
    np.testing.assert_allclose(yaw_quaternions(theta), expected, atol=1e-15)


def test_write_then_read_round_trips_planar_poses_exactly(tmp_path):
    rng = np.random.default_rng(0)
    poses = np.column_stack([rng.uniform(-20, 20, (50, 2)), rng.uniform(-math.pi, math.pi, 50)])
    stamps = 0.1 * np.arange(1, 51)
    path = write_tum(tmp_path / "a.tum", stamps, poses)
    lines = path.read_text().splitlines()
    assert lines[0] == "# timestamp tx ty tz qx qy qz qw" and len(lines) == 51
    first = lines[1].split(" ")
    assert len(first) == 8 and first[0] == "0.100000000" and float(first[3]) == 0.0  # z = 0
    read_stamps, read_poses = read_tum(path)
    np.testing.assert_allclose(read_stamps, stamps, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(read_poses[:, :2], poses[:, :2])  # written with every digit float64 has
    np.testing.assert_allclose(wrap_angles(read_poses[:, 2] - poses[:, 2]), 0.0, atol=1e-12)


def test_bad_shapes_and_files_are_refused(tmp_path):
    with pytest.raises(ValueError, match="T, 3"):
        write_tum(tmp_path / "b.tum", np.arange(3.0), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="finite"):
        write_tum(tmp_path / "c.tum", np.arange(2.0), np.array([[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]]))
    bad = tmp_path / "bad.tum"
    bad.write_text("0 1 2 3 0 0 0\n")
    with pytest.raises(ValueError, match="needs 8 values"):
        read_tum(bad)


def test_landmark_csv_has_nan_for_unseen_estimates(tmp_path):
    true = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]])
    estimated = true + 0.25
    path = write_landmarks_csv(tmp_path / "m.csv", true, estimated, np.array([True, False, True]))
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    assert tuple(rows[0]) == LANDMARK_COLUMNS
    assert [r["id"] for r in rows] == ["0", "1", "2"] and [r["seen"] for r in rows] == ["1", "0", "1"]
    assert float(rows[2]["true_y"]) == 6.0 and float(rows[2]["estimated_x"]) == 5.25
    assert math.isnan(float(rows[1]["estimated_x"])) and math.isnan(float(rows[1]["estimated_y"]))
    with pytest.raises(ValueError, match="lengths disagree"):
        write_landmarks_csv(tmp_path / "n.csv", true, estimated[:2], np.ones(3, bool))


# ------------------------------------------------------------------------------- evaluate --export-tum


def _read_landmarks(path):
    with open(path) as handle:
        return list(csv.DictReader(handle))


def test_export_tum_writes_both_trajectories_and_the_map_of_every_episode(tmp_path, capsys):
    tum, rows_json = tmp_path / "tum", tmp_path / "episodes.json"
    argv = ["--agent", "greedy", "--seeds", "3-4", "--max-episode-steps", "40", "--no-progress", "--json",
            "--export-tum", str(tum), "--episodes-json", str(rows_json)]  # fmt: skip
    assert evaluate_main(argv) == 0
    json.loads(capsys.readouterr().out)  # stdout is still exactly one JSON object
    rows = json.loads(rows_json.read_text())["greedy"]
    kinds = ("estimate.tum", "landmarks.csv", "true.tum")
    assert sorted(p.name for p in tum.iterdir()) == [f"greedy_{s}_{k}" for s in (3, 4) for k in kinds]
    for row in rows:
        stem = tum / f"greedy_{row['seed']}"
        stamps, true = read_tum(f"{stem}_true.tum")
        estimate_stamps, estimate = read_tum(f"{stem}_estimate.tum")
        np.testing.assert_allclose(stamps, 0.1 * np.arange(1, 41), rtol=0, atol=1e-12)  # step * dt
        np.testing.assert_array_equal(estimate_stamps, stamps)
        assert metrics.ate(estimate, true) == pytest.approx(row["ate"], rel=1e-12)
        landmarks = _read_landmarks(f"{stem}_landmarks.csv")
        seen = [r for r in landmarks if r["seen"] == "1"]
        assert len(landmarks) == 30 and len(landmarks) - len(seen) == row["missed_landmarks"]
        true_xy = np.array([[float(r["true_x"]), float(r["true_y"])] for r in seen])
        estimated_xy = np.array([[float(r["estimated_x"]), float(r["estimated_y"])] for r in seen])
        rmse, _ = metrics.landmark_errors(estimated_xy, true_xy, np.ones(len(seen), bool))
        assert rmse == pytest.approx(row["landmark_rmse"], rel=1e-12)
        assert all(math.isnan(float(r["estimated_x"])) for r in landmarks if r["seen"] == "0")


def test_run_episode_hands_over_the_scored_trajectories_without_changing_the_metrics(tmp_path):
    env = make_env("EKFSLAM-v0", max_episode_steps=30)
    plain = run_episode(env, make_agent("circle"), 2)
    handed = []
    with_export = run_episode(env, make_agent("circle"), 2, trajectories=lambda *poses: handed.append(poses))
    env.close()
    assert with_export == plain
    ((true, estimated),) = handed
    assert true.shape == estimated.shape == (30, 3)
    assert metrics.ate(estimated, true) == plain["ate"]


def test_evo_reads_the_exported_files_and_its_unaligned_ape_is_the_ate(tmp_path):
    pytest.importorskip("evo")
    from evo.core.metrics import PoseRelation
    from evo.main_ape import ape
    from evo.tools import file_interface

    env = make_env("EKFSLAM-v0", max_episode_steps=60)
    trajectories = {}

    def export(true, estimated):
        trajectories.update(true=true, estimated=estimated)
        export_tum(tmp_path, "random", 5, env, true, estimated)

    row = run_episode(env, make_agent("random"), 5, trajectories=export)
    env.close()
    true = file_interface.read_tum_trajectory_file(tmp_path / "random_5_true.tum")
    estimate = file_interface.read_tum_trajectory_file(tmp_path / "random_5_estimate.tum")
    assert true.num_poses == estimate.num_poses == 60 and row["ate"] > 0
    np.testing.assert_allclose(true.timestamps, 0.1 * np.arange(1, 61), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(estimate.positions_xyz[:, :2], trajectories["estimated"][:, :2])
    np.testing.assert_array_equal(true.positions_xyz[:, 2], 0.0)

    result = ape(true, estimate, PoseRelation.translation_part, align=False, correct_scale=False)
    assert result.stats["rmse"] == pytest.approx(row["ate"], rel=1e-9)

    # evo reads the quaternion as the heading: its yaw is ours, its rotation error per pose our heading error
    yaw = true.get_orientations_euler()[:, 2]
    np.testing.assert_allclose(wrap_angles(yaw - trajectories["true"][:, 2]), 0.0, atol=1e-12)
    angles = ape(true, estimate, PoseRelation.rotation_angle_rad, align=False, correct_scale=False)
    heading_errors = metrics.pose_errors(trajectories["estimated"], trajectories["true"])[:, 2]
    np.testing.assert_allclose(angles.np_arrays["error_array"], np.abs(heading_errors), atol=1e-9)


# ------------------------------------------------------------------------------------------ replay --tum


def test_replay_tum_writes_the_estimate_and_for_the_simulated_drive_the_truth(tmp_path, capsys):
    path = tmp_path / "drive.tum"
    assert replay_main(["--steps", "60", "--tum", str(path), "--json"]) == 0
    captured = capsys.readouterr()
    result = json.loads(captured.out)  # stdout stays one JSON object; the file note goes to stderr
    assert f"to {tmp_path / 'drive_true.tum'}" in captured.err
    stamps, estimate = read_tum(path)
    true_stamps, true = read_tum(tmp_path / "drive_true.tum")
    np.testing.assert_array_equal(stamps, np.arange(61.0))  # no clock in the course format: t = step
    np.testing.assert_array_equal(true_stamps, stamps)
    np.testing.assert_array_equal(estimate[0], 0.0)  # the course's start: the origin, known
    np.testing.assert_array_equal(estimate[-1, :2], result["pose"][:2])
    assert abs(wrap_angles(estimate[-1, 2] - result["pose"][2])) < 1e-12
    expected = simulate_drive(0).poses[:61]
    np.testing.assert_array_equal(true[:, :2], expected[:, :2])
    np.testing.assert_allclose(wrap_angles(true[:, 2] - expected[:, 2]), 0.0, atol=1e-12)

    evo = pytest.importorskip("evo.main_ape")
    from evo.core.metrics import PoseRelation
    from evo.tools import file_interface

    files = [file_interface.read_tum_trajectory_file(p) for p in (tmp_path / "drive_true.tum", path)]
    rmse = evo.ape(*files, PoseRelation.translation_part, align=False).stats["rmse"]
    assert rmse == pytest.approx(metrics.ate(estimate, expected), rel=1e-9)


def test_replay_tum_of_course_files_writes_only_the_estimate(tmp_path, capsys):
    data_path, world_path = simulate_drive(0).write(tmp_path / "files")
    out = tmp_path / "f.tum"
    assert replay_main(["--data", str(data_path), "--world", str(world_path), "--steps", "10", "--tum", str(out)]) == 0  # fmt: skip
    assert f"wrote the estimated trajectory (TUM) to {out} (no true trajectory)" in capsys.readouterr().out
    assert read_tum(out)[1].shape == (11, 3)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.tum", "files"]  # course files carry no truth


def test_replay_tum_into_a_missing_directory_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exit_info:
        replay_main(["--tum", "/no/such/dir/run.tum"])
    assert exit_info.value.code == 2 and "does not exist" in capsys.readouterr().err
