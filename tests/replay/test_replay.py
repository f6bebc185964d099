"""The replay entry point: the course anchors, its JSON/npz/picture outputs and its error messages."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ekfslam_gym.cli.replay import main
from ekfslam_gym.data.course import read_sensor_data, read_world
from ekfslam_gym.data.synthetic import simulate_drive
from ekfslam_gym.replay.course import final_frame, map_errors, map_rmse, replay
from tests.datapaths import freiburg_dir


@pytest.fixture(scope="module")
def course():
    folder = freiburg_dir()
    if folder is None or not all((folder / name).is_file() for name in ("sensor_data.dat", "world.dat")):
        pytest.skip("course data not found: set EKFSLAM_DATA_DIR or put it in ../shared/data/freiburg")
    return folder / "sensor_data.dat", folder / "world.dat"


def run_json(capsys, *argv: str) -> dict:
    assert main([*map(str, argv), "--json"]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1  # exactly one JSON object, nothing else on stdout
    return json.loads(out)


# ---------------------------------------------------------------- the course anchors (README, data/freiburg)

ANCHORS = {
    330: {
        "pose": (5.022429, 4.618957, 1.542055),
        "cov": (0.166222, 0.174189, 0.00405974),
        "landmarks": {
            1: (1.805560, 0.837339), 2: (-0.115657, 3.876012), 3: (1.997724, 6.822630),
            4: (8.848477, 1.645002), 5: (9.948596, 4.625712), 6: (9.014044, 7.629533),
            7: (4.927556, 4.779196), 8: (4.865821, 2.764155), 9: (5.009379, 8.776412),
        },
    },
    331: {
        "pose": (4.964948, 4.741379, 1.512972),
        "cov": (0.171800, 0.172052, 0.00408396),
        "landmarks": {
            1: (1.805097, 0.838391), 2: (-0.117744, 3.875795), 3: (1.996410, 6.822339),
            4: (8.846650, 1.649742), 5: (9.944577, 4.630954), 6: (9.005313, 7.632987),
            7: (4.925093, 4.781241), 8: (4.864386, 2.768134), 9: (5.002936, 8.784729),
        },
    },
}  # fmt: skip


@pytest.mark.parametrize("steps", [330, 331])
def test_course_anchors(course, capsys, steps):
    data, world = course
    argv = ["--data", data, "--world", world] + (["--steps", steps] if steps == 330 else [])  # 331 = default
    result = run_json(capsys, *argv)
    anchor = ANCHORS[steps]
    assert result["steps"] == steps
    np.testing.assert_allclose(result["pose"], anchor["pose"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.diagonal(result["pose_cov"]), anchor["cov"], rtol=0, atol=1e-6)
    assert sorted(result["landmarks"]) == [str(i) for i in range(1, 10)]
    for landmark, xy in anchor["landmarks"].items():
        np.testing.assert_allclose(result["landmarks"][str(landmark)], xy, rtol=0, atol=1e-6)


def test_course_sequential_variant(course, capsys):
    """One 2x2 update per reading, relinearising: menashe-soffer's solution in the README."""
    data, world = course
    result = run_json(capsys, "--data", data, "--world", world, "--steps", 330, "--sequential")
    np.testing.assert_allclose(result["pose"], (4.831083, 4.806494, 1.584268), rtol=0, atol=1e-6)


def test_without_world_slots_follow_the_ids(course, capsys):
    data, world = course
    with_world = run_json(capsys, "--data", data, "--world", world, "--steps", 50)
    without = run_json(capsys, "--data", data, "--steps", 50)
    assert without == with_world  # world ids are 1..9, the same slots as "max id seen"


def test_inverse_initialisation_runs(course, capsys):
    data, world = course
    course_init = run_json(capsys, "--data", data, "--world", world, "--steps", 100)
    inverse = run_json(capsys, "--data", data, "--world", world, "--steps", 100, "--init", "inverse")
    assert inverse["pose"] != course_init["pose"]
    assert np.isfinite(inverse["log_det"])
    assert np.linalg.norm(np.subtract(inverse["pose"][:2], course_init["pose"][:2])) < 0.5


# --------------------------------------------------------------------------------------- outputs and schema


def test_json_schema_on_the_simulated_drive(capsys):
    result = run_json(capsys, "--steps", 120, "--seed", 3)
    assert set(result) == {"steps", "pose", "pose_cov", "landmarks", "log_det"}
    assert result["steps"] == 120 and isinstance(result["steps"], int)
    assert len(result["pose"]) == 3 and all(isinstance(v, float) for v in result["pose"])
    cov = np.array(result["pose_cov"])
    assert cov.shape == (3, 3) and np.allclose(cov, cov.T) and np.all(np.linalg.eigvalsh(cov) > 0)
    assert isinstance(result["log_det"], float) and np.isfinite(result["log_det"])
    drive = simulate_drive(3)
    seen = {int(i) for step in drive.data.steps[:120] for i in step.ids}
    assert {int(k) for k in result["landmarks"]} == seen  # observed ones only, by file id
    assert all(len(v) == 2 for v in result["landmarks"].values())


def test_save_state_contents(tmp_path, capsys):
    path = tmp_path / "state.npz"
    result = run_json(capsys, "--steps", 80, "--save-state", path)
    with np.load(path) as state:
        mean, cov, log_det = state["mean"], state["cov"], float(state["log_det"])
    n = 16  # landmarks of the default drive
    assert mean.shape == (3 + 2 * n,) and cov.shape == (3 + 2 * n, 3 + 2 * n)
    np.testing.assert_array_equal(mean[:3], result["pose"])
    np.testing.assert_array_equal(cov[:3, :3], result["pose_cov"])
    assert log_det == result["log_det"]
    sign, slogdet = np.linalg.slogdet(cov)
    assert sign == 1 and abs(log_det - slogdet) <= 1e-8 * max(1.0, abs(slogdet))


def test_default_run_prints_a_summary_and_draws(tmp_path, capsys):
    png = tmp_path / "belief.png"
    assert main(["--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "final pose" in out and "map RMSE vs world" in out and str(png) in out
    rmse = float(out.split("map RMSE vs world:")[1].split()[0])
    assert rmse < 0.3  # the filter maps the simulated field to within a few decimetres
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000


def test_gif_has_frames(tmp_path, capsys):
    import imageio.v3 as iio

    gif = tmp_path / "drive.gif"
    assert main(["--steps", "5", "--gif", str(gif), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["steps"] == 5
    frames = iio.imread(gif, index=None)
    assert frames.shape[0] == 5 and frames.shape[-1] in (3, 4)


def test_replay_function_matches_the_cli(capsys):
    drive = simulate_drive(0)
    result = replay(drive.data, world=drive.world, steps=60, true_poses=drive.poses, frame_every=20)
    assert [f.step for f in result.extras["frames"]] == [20, 40, 60]
    assert run_json(capsys, "--steps", 60)["pose"] == [float(v) for v in result.ekf.pose]
    assert map_rmse(result, drive.world) is not None
    assert set(map_errors(result, drive.world)) == set(result.landmark_estimates())
    np.testing.assert_array_equal(result.poses[-1], result.ekf.pose)
    assert result.steps == 60 and result.seconds > 0


# ------------------------------------------------------------------------------------------------- errors


def _fails(capsys, argv, fragment):
    with pytest.raises(SystemExit) as info:
        main([str(a) for a in argv])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err
    return err


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["--steps", "0"], "--steps must be a positive"),
        (["--steps", "-4"], "--steps must be a positive"),
        (["--steps", "100000"], "has only 468 steps"),
        (["--world", "world.dat"], "--world needs --data"),
        (["--data", "/no/such/sensor_data.dat"], "no such file: /no/such/sensor_data.dat"),
        (["--plot", "picture.jpg"], "--plot needs a .png"),
        (["--save-state", "/no/such/dir/state.npz"], "does not exist"),
        (["--init", "magic"], "invalid choice"),
    ],
)
def test_usage_errors(capsys, argv, fragment):
    _fails(capsys, argv, fragment)


def test_malformed_and_inconsistent_files(tmp_path, capsys):
    data = tmp_path / "sensor_data.dat"
    world = tmp_path / "world.dat"
    world.write_text("1 0 1\n2 3 4\n")
    data.write_text("ODOMETRY 0 0.1 0\nSENSOR 1 1.0 0.5\nODOMETRY 0 0.1\n")
    _fails(capsys, ["--data", data], "sensor_data.dat:3:")
    data.write_text("ODOMETRY 0 0.1 0\nSENSOR 1 1.0 0.5\nODOMETRY 0 0.1 0\nSENSOR 7 2.0 0.1\n")
    _fails(capsys, ["--data", data, "--world", world], "id(s) [7] not in the world file")
    _fails(capsys, ["--data", data, "--seed", "1"], "--seed applies to the simulated drive only")


def test_course_format_files_replay_like_the_drive(tmp_path, capsys):
    drive = simulate_drive(0)
    data_path, world_path = drive.write(tmp_path)
    from_files = run_json(capsys, "--data", data_path, "--world", world_path, "--steps", 40)
    assert from_files == run_json(capsys, "--steps", 40)
    assert read_world(world_path).positions.shape == (16, 2) and len(read_sensor_data(data_path)) == 468


# ------------------------------------------------------------------------------------------------ plotting


def test_pictures_leave_pyplot_alone(tmp_path):
    import sys

    from ekfslam_gym.evaluation import plotting

    had_pyplot = "matplotlib.pyplot" in sys.modules
    drive = simulate_drive(1)
    result = replay(drive.data, world=drive.world, steps=30, true_poses=drive.poses)
    plotting.save_png(tmp_path / "a.png", final_frame(result), drive.world)
    assert ("matplotlib.pyplot" in sys.modules) == had_pyplot  # drawn on a bare Figure, no global state
    assert (tmp_path / "a.png").stat().st_size > 10_000


def test_belief_from_state_reads_the_filter_blocks():
    from ekfslam_gym.evaluation.plotting import Belief

    drive = simulate_drive(2)
    ekf = replay(drive.data, world=drive.world, steps=50).ekf
    belief = Belief.from_state(ekf.mean, ekf.cov, ekf.observed)
    np.testing.assert_array_equal(belief.landmarks, ekf.landmarks)
    np.testing.assert_array_equal(belief.landmark_covs, ekf.landmark_covs())
    np.testing.assert_array_equal(belief.pose_cov, ekf.pose_cov)
