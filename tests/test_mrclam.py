"""The MRCLAM reader on excerpts written here, and the filter on the full drive where the data set is present
(../shared/data/mrclam, see tests/datapaths.py; those tests skip cleanly without it)."""

from __future__ import annotations

import numpy as np
import pytest

from ekfslam_gym.data.mrclam import (
    load_mrclam,
    read_barcodes,
    read_landmark_truth,
    read_measurements,
    read_odometry,
)
from ekfslam_gym.evaluation.alignment import align_se2
from ekfslam_gym.evaluation.mrclam import ReplaySettings, build_drive, landmark_errors, replay_drive
from tests.datapaths import mrclam_dir

# Excerpts in the data set's own layout (tab-separated, '#' headers); _folder adds the trailing blank its lines have.
BARCODES = """# UTIAS Multi-Robot Cooperative Localization and Mapping Dataset
# Subject #    Barcode #
  1 \t   5
  2 \t  14
  6 \t  72
  7 \t  27
"""
LANDMARKS = """  6 \t 5.70928255 \t 4.96404466 \t 0.00027464 \t 0.00041465
  7 \t 5.25292609 \t 5.53656921 \t 0.00011889 \t 0.00035386
"""
ODOMETRY = """# Time [s]    Forward Velocity [m/s]    Angular Velocity [rad/s]
1248272272.841 \t  0.074 \t  0.229
1248272272.852 \t  0.074 \t  0.229
1248272273.852 \t  0.000 \t  0.500
1248272274.852 \t  0.100 \t  0.000
"""
MEASUREMENTS = """1248272273.000 \t  72 \t  2.148 \t  0.025
1248272273.000 \t  14 \t  3.387 \t  0.006
1248272274.000 \t  27 \t  3.309 \t -0.015
"""


def _folder(tmp_path, **overrides):
    files = {
        "Barcodes.dat": BARCODES,
        "Landmark_Groundtruth.dat": LANDMARKS,
        "Robot1_Odometry.dat": ODOMETRY,
        "Robot1_Measurement.dat": MEASUREMENTS,
        **overrides,
    }
    for name, text in files.items():
        (tmp_path / name).write_text(text.replace("\n", " \n"))
    return tmp_path


def test_readers_on_excerpts(tmp_path):
    folder = _folder(tmp_path)
    odometry = read_odometry(folder / "Robot1_Odometry.dat")
    np.testing.assert_array_equal(odometry.v, [0.074, 0.074, 0.0, 0.1])
    np.testing.assert_array_equal(odometry.omega, [0.229, 0.229, 0.5, 0.0])
    assert odometry.time[0] == 1248272272.841
    readings = read_measurements(folder / "Robot1_Measurement.dat")
    assert readings.barcode.tolist() == [72, 14, 27]
    np.testing.assert_array_equal(readings.z[2], [3.309, -0.015])
    assert read_barcodes(folder / "Barcodes.dat") == {1: 5, 2: 14, 6: 72, 7: 27}
    landmarks, std = read_landmark_truth(folder / "Landmark_Groundtruth.dat")
    assert landmarks.ids.tolist() == [6, 7]
    np.testing.assert_array_equal(landmarks.positions[1], [5.25292609, 5.53656921])
    np.testing.assert_array_equal(std[0], [0.00027464, 0.00041465])


def test_other_robots_are_not_landmarks(tmp_path):
    run = load_mrclam(_folder(tmp_path))
    assert run.subjects().tolist() == [6, 2, 7]
    readings, subjects = run.landmark_readings()
    assert subjects.tolist() == [6, 7] and readings.barcode.tolist() == [72, 27]
    assert len(build_drive(run).z) == 2
    assert build_drive(run, robots=True).subject.tolist() == [6, 2, 7]


def test_drive_holds_each_command_until_the_next(tmp_path):
    drive = build_drive(load_mrclam(_folder(tmp_path)))
    # breaks at the first record, the command changes and the readings' times; each step holds its command
    assert drive.time[0] == pytest.approx(1248272272.841)
    assert np.sum(drive.increments[:, 0]) == pytest.approx(0.074 * 1.011, abs=1e-6)
    assert np.sum(drive.increments[:, 1]) == pytest.approx(0.229 * 1.011 + 0.5 * 1.0, abs=1e-6)
    ends = drive.time[1:][np.diff(drive.offsets) > 0]
    np.testing.assert_allclose(ends, [1248272273.0, 1248272274.0])
    merged = build_drive(load_mrclam(_folder(tmp_path)), merge=10.0)
    assert len(merged) == 3  # one step up to each reading time, one from the last reading to the end
    np.testing.assert_allclose(merged.increments.sum(axis=0), drive.increments.sum(axis=0))


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        ("Robot1_Odometry.dat", "1.0 0.1\n", "Robot1_Odometry.dat:1: odometry (time v omega) line needs 3"),
        (
            "Robot1_Odometry.dat",
            "# head\n1.0 0.1 0.0\n2.0 0.1 x\n",
            "Robot1_Odometry.dat:3: omega 'x' is not",
        ),
        ("Robot1_Odometry.dat", "2.0 0.1 0.0\n1.0 0.1 0.0\n", "Robot1_Odometry.dat:2: time 1.0 goes back"),
        (
            "Robot1_Measurement.dat",
            "1.0 72 -2.0 0.1\n",
            "Robot1_Measurement.dat:1: range '-2.0' is not positive",
        ),
        (
            "Robot1_Measurement.dat",
            "1.0 7.5 2.0 0.1\n",
            "Robot1_Measurement.dat:1: barcode '7.5' is not an integer",
        ),
        ("Robot1_Measurement.dat", "1.0 72 nan 0.1\n", "Robot1_Measurement.dat:1: range 'nan' is not finite"),
        ("Barcodes.dat", "1 5\n2 5\n", "Barcodes.dat:2: barcode 5 already belongs"),
        (
            "Landmark_Groundtruth.dat",
            "6 1 2 0 0\n6 1 2 0 0\n",
            "Landmark_Groundtruth.dat:2: landmark subject 6",
        ),
    ],
)
def test_errors_name_file_and_line(tmp_path, name, text, message):
    folder = _folder(tmp_path, **{name: text})
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        run = load_mrclam(folder)
        run.odometry  # noqa: B018


def test_robot_subject_listed_as_landmark_is_refused(tmp_path):
    folder = _folder(tmp_path, **{"Landmark_Groundtruth.dat": LANDMARKS + "2 1.0 1.0 0 0\n"})
    with pytest.raises(ValueError, match=r"subjects \[2\] are robots"):
        load_mrclam(folder)


def test_missing_file_is_named(tmp_path):
    folder = _folder(tmp_path)
    (folder / "Robot1_Measurement.dat").unlink()
    with pytest.raises(FileNotFoundError, match="Robot1_Measurement.dat"):
        load_mrclam(folder)


def test_se2_alignment_recovers_a_rigid_motion():
    rng = np.random.default_rng(0)
    points = rng.uniform(-5, 5, (15, 2))
    angle, shift = 2.5, np.array([3.0, -1.0])
    c, s = np.cos(angle), np.sin(angle)
    moved = points @ np.array([[c, -s], [s, c]]).T + shift
    transform = align_se2(points, moved)
    assert transform.angle == pytest.approx(angle)
    np.testing.assert_allclose(transform.translation, shift)
    np.testing.assert_allclose(transform.points(points), moved, atol=1e-12)


# ------------------------------------------------------------------------------------------------- full data


def _run():
    folder = mrclam_dir()
    if folder is None:
        pytest.skip("MRCLAM data set 1 not found: ../shared/data/mrclam (or set EKFSLAM_MRCLAM_DIR)")
    return load_mrclam(folder)


def test_full_files_read():
    run = _run()
    assert len(run.odometry) == 97890 and len(run.measurements) == 5723
    assert run.landmarks.ids.tolist() == list(range(6, 21))
    assert int(run.is_landmark_reading().sum()) == 4771  # the rest read the other four robots
    assert set(run.subjects()[~run.is_landmark_reading()].tolist()) == {2, 3, 4, 5}


@pytest.mark.slow
def test_filter_map_meets_the_textbook_ekf():
    """The textbook dense EKF-SLAM (known barcodes, range sigma 0.15 m, bearing sigma 0.08 rad, velocity model):
    13 of 15 landmarks within 0.18 m of the survey after the best SE(2) alignment, median 0.08 m."""
    run = _run()
    result = replay_drive(
        build_drive(run), run.landmarks.ids, ReplaySettings(range_std=0.15, bearing_std=0.08)
    )
    errors, _ = landmark_errors(result.landmark_estimates(), run.landmarks.ids, run.landmarks.positions)
    values = np.array(list(errors.values()))
    assert len(values) == 15
    assert np.median(values) <= 0.08
    assert np.sum(values <= 0.18) >= 13
    assert 0 < np.mean(result.nis) < 10
