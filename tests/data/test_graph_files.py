"""The graph data sets of the Freiburg *Robot Mapping* course (C. Stachniss; its least-squares SLAM exercise)
through the MAT and g2o readers, and the g2o writer.

The data is never copied into the repository: ``tests/datapaths.py`` finds it ($EKFSLAM_DATA_DIR or its default
folder); these tests skip where it is absent.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ekfslam_gym.cli.graph import main as graph_cli
from ekfslam_gym.data.g2o import read_g2o, write_g2o
from ekfslam_gym.data.graph_files import read_graph
from ekfslam_gym.data.matfile import read_mat_graph
from ekfslam_gym.graph.optimizer import FactorGraph, Values, gauss_newton, levenberg_marquardt
from tests.datapaths import freiburg_dir


@pytest.fixture(scope="module")
def freiburg() -> Path:
    path = freiburg_dir()
    if path is None:
        pytest.skip(
            "Freiburg course data not found: set $EKFSLAM_DATA_DIR to its folder (see tests/datapaths.py)"
        )
    return path


def _data_file(freiburg: Path, name: str) -> Path:
    path = freiburg / name
    if not path.is_file():
        pytest.skip(f"{name} is not in {freiburg}")
    return path


# (file, the course's final error, the initial error as we reproduce it, GN iterations).
ANCHORS = [
    ("simulation-pose-pose.dat", 8269.0, 138_862_234.08, 9),
    ("intel.dat", 360.0, 1_795_138.99, 5),
    ("simulation-pose-landmark.dat", 474.0, 3_030.31, 4),
    ("dlr.g2o", 56860.0, 369_655_329.23, 10),
    ("simulation-pose-pose.g2o", 8269.0, 138_862_238.43, 9),
    ("intel.g2o", 360.0, 1_795_139.01, 5),
    ("simulation-pose-landmark.g2o", 474.0, 3_030.31, 4),
]
BOTH_FORMS = ["simulation-pose-pose", "intel", "simulation-pose-landmark"]


@pytest.mark.parametrize(("name", "final", "initial", "iterations"), ANCHORS, ids=[a[0] for a in ANCHORS])
def test_course_anchor(freiburg, name, final, initial, iterations):
    problem = read_graph(_data_file(freiburg, name))
    result = gauss_newton(problem.graph, problem.initial)
    assert result.converged
    assert result.initial_error == pytest.approx(initial, abs=0.01)
    assert result.final_error == pytest.approx(final, rel=1e-3)  # the course's figures are rounded
    assert result.iterations == iterations
    assert len(result.errors) == iterations + 1


def test_sizes_match_the_readme(freiburg):
    sizes = {  # poses, landmarks, pose-pose edges, pose-landmark edges
        "simulation-pose-pose.dat": (400, 0, 1773, 0),
        "simulation-pose-landmark.dat": (41, 36, 40, 257),
        "intel.dat": (1728, 0, 4830, 0),
        "dlr.g2o": (3297, 576, 3296, 14309),
    }
    for name, (poses, landmarks, pp, pl) in sizes.items():
        problem = read_graph(_data_file(freiburg, name))
        assert problem.initial.num_poses == poses and problem.initial.num_landmarks == landmarks
        assert len(problem.graph.between) == pp and len(problem.graph.pose_landmark) == pl


@pytest.mark.parametrize("name", BOTH_FORMS)
def test_mat_and_g2o_agree(freiburg, name):
    mat = read_mat_graph(_data_file(freiburg, name + ".dat"))
    txt = read_g2o(_data_file(freiburg, name + ".g2o"))
    np.testing.assert_array_equal(mat.pose_ids, txt.pose_ids)
    np.testing.assert_array_equal(mat.landmark_ids, txt.landmark_ids)
    # The g2o files are the MAT contents printed with 6 decimals; information matrices are bit-identical.
    np.testing.assert_allclose(mat.initial.poses, txt.initial.poses, atol=6e-7)
    np.testing.assert_allclose(mat.initial.landmarks, txt.initial.landmarks, atol=6e-7)
    for kind in ("between", "pose_landmark"):
        a, b = mat.graph.factors(kind), txt.graph.factors(kind)
        np.testing.assert_array_equal(a.first, b.first)
        np.testing.assert_array_equal(a.second, b.second)
        np.testing.assert_allclose(a.measured, b.measured, atol=6e-7)
        np.testing.assert_array_equal(a.information, b.information)
    r_mat = gauss_newton(mat.graph, mat.initial)
    r_txt = gauss_newton(txt.graph, txt.initial)
    assert r_mat.final_error == pytest.approx(r_txt.final_error, rel=1e-5)
    np.testing.assert_allclose(r_mat.values.poses[:, :2], r_txt.values.poses[:, :2], atol=1e-4)
    np.testing.assert_allclose(r_mat.values.landmarks, r_txt.values.landmarks, atol=1e-4)


@pytest.mark.parametrize("name", ["intel.g2o", "dlr.g2o", "simulation-pose-landmark.dat"])
def test_g2o_round_trip_is_exact(freiburg, name, tmp_path):
    problem = read_graph(_data_file(freiburg, name))
    out = tmp_path / "copy.g2o"
    write_g2o(out, problem.graph, problem.initial, problem.pose_ids, problem.landmark_ids)
    again = read_g2o(out)
    np.testing.assert_array_equal(again.pose_ids, problem.pose_ids)
    np.testing.assert_array_equal(again.landmark_ids, problem.landmark_ids)
    np.testing.assert_array_equal(again.initial.poses, problem.initial.poses)
    np.testing.assert_array_equal(again.initial.landmarks, problem.initial.landmarks)
    for kind in ("between", "pose_landmark"):
        a, b = problem.graph.factors(kind), again.graph.factors(kind)
        for field in ("first", "second", "measured", "information"):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def test_levenberg_marquardt_reaches_the_intel_optimum(freiburg):
    problem = read_graph(_data_file(freiburg, "intel.dat"))
    gn = gauss_newton(problem.graph, problem.initial)
    lm = levenberg_marquardt(problem.graph, problem.initial)
    assert lm.converged
    assert lm.final_error == pytest.approx(gn.final_error, rel=1e-6)
    assert np.all(np.diff(lm.errors) < 0)


def test_cli_json_on_intel(freiburg, capsys):
    assert graph_cli([str(_data_file(freiburg, "intel.dat")), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["poses"] == 1728 and summary["landmarks"] == 0 and summary["iterations"] == 5
    assert summary["initial_error"] == pytest.approx(1_795_138.99, abs=0.01)
    assert summary["final_error"] == pytest.approx(360.0, rel=1e-3)


# --------------------------------------------------------------------------------------------------------------
# Malformed input (no course data needed)

GOOD = [
    "VERTEX_SE2 0 0 0 0",
    "VERTEX_SE2 1 1 0 0",
    "VERTEX_XY 7 1 1",
    "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1",
    "EDGE_SE2_XY 1 7 0 1 1 0 1",
]


def test_g2o_reader_accepts_comments_blank_lines_and_any_order(tmp_path):
    path = tmp_path / "ok.g2o"
    path.write_text("# a comment\n\n" + "\n".join(reversed(GOOD)) + "  # trailing\n")
    problem = read_g2o(path)
    assert problem.initial.num_poses == 2 and problem.initial.num_landmarks == 1
    np.testing.assert_array_equal(problem.pose_ids, [1, 0])  # file order
    np.testing.assert_array_equal(problem.landmark_ids, [7])
    assert len(problem.graph.between) == 1 and len(problem.graph.pose_landmark) == 1


@pytest.mark.parametrize(
    ("line_no", "line", "message"),
    [
        (2, "VERTEX_SE2 1 1 0", "needs 4 values, got 3"),
        (4, "EDGE_SE2 0 1 1 0 0 1 0 0 1 0", "needs 11 values, got 10"),
        (3, "VERTEX_XY 7 1 one", "malformed VERTEX_XY"),
        (1, "VERTEX_SE2 0.5 0 0 0", "malformed VERTEX_SE2"),
        (3, "VERTEX_XY 1 1 1", "vertex 1 defined twice"),
        (5, "EDGE_SE2_XY 1 8 0 1 1 0 1", "8, which is not a VERTEX_XY"),
        (4, "EDGE_SE2 0 7 1 0 0 1 0 0 1 0 1", "7, which is not a VERTEX_SE2"),
        (3, "VERTEX_XY 7 nan 1", "non-finite"),
        (4, "EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1", "unsupported tag"),
    ],
)
def test_g2o_reader_names_file_and_line(tmp_path, line_no, line, message):
    lines = list(GOOD)
    lines[line_no - 1] = line
    path = tmp_path / "bad.g2o"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=f"bad.g2o:{line_no}: .*{message}"):
        read_g2o(path)


def test_g2o_writer_refuses_what_the_format_cannot_hold(tmp_path):
    g = FactorGraph()
    g.add_range_bearing(0, 0, [1.0, 0.0], np.eye(2))
    with pytest.raises(ValueError, match="cannot store range_bearing"):
        write_g2o(tmp_path / "x.g2o", g, Values([[0.0, 0.0, 0.0]], [[1.0, 0.0]]))


def test_mat_reader_rejects_other_files(tmp_path):
    import scipy.io

    path = tmp_path / "other.dat"
    scipy.io.savemat(path, {"h": np.eye(2)})
    with pytest.raises(ValueError, match="other.dat"):
        read_mat_graph(path)
    path.write_bytes(b"not a MAT file at all")
    with pytest.raises(ValueError, match="other.dat"):
        read_mat_graph(path)
