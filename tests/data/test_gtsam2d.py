"""The GTSAM 2-D dataset reader on small excerpts written here, checked by hand and, where GTSAM is installed (the
`bench` extra), against GTSAM's own load2D."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ekfslam_gym.data.graph_files import read_graph
from ekfslam_gym.data.gtsam2d import read_gtsam2d
from ekfslam_gym.graph import se2

# The first lines of GTSAM's examples/Data/victoria_park.txt (BSD licence, GTSAM-LICENSE.BSD; see the
# data folder's README for provenance): odometry, then a landmark seen twice from different poses.
VICTORIA_PARK_HEAD = """\
ODOMETRY 0 1 0.000985144 -3.63222e-10 -1.54136e-06 0.0001 0 0 4e-06 0 4e-06
ODOMETRY 1 2 0.00492658 -1.35875e-08 -6.57618e-06 0.0001 0 0 4e-06 0 4e-06
ODOMETRY 2 3 0.0265992 -4.82655e-07 -4.12159e-05 0.0001 0 0 4e-06 0 4e-06
ODOMETRY 3 4 0.0640488 -2.22135e-06 -8.11689e-05 0.0001 0 0 4e-06 0 4e-06
LANDMARK 4 5 11.5387 -3.2007 0.4 0 0.4
ODOMETRY 4 6 0.08819 -4.08686e-06 -0.000112047 0.0001 0 0 4e-06 0 4e-06
ODOMETRY 6 7 0.136021 -7.5832e-06 -0.000118978 0.0001 0 0 4e-06 0 4e-06
ODOMETRY 7 8 0.176976 -7.23341e-06 -8.91877e-05 0.0001 0 0 4e-06 0 4e-06
LANDMARK 8 9 15.2622 4.67917 0.4 0 0.4
ODOMETRY 8 10 0.191832 -8.47413e-07 -7.73962e-06 0.0001 0 0 4e-06 0 4e-06
ODOMETRY 10 11 0.251039 1.95395e-06 2.82921e-05 0.0001 0 0 4e-06 0 4e-06
LANDMARK 11 5 10.7274 -3.194 0.4 0 0.4
"""


@pytest.fixture
def write(tmp_path):
    def _write(text: str, name: str = "graph.txt"):
        path = tmp_path / name
        path.write_text(text)
        return path

    return _write


def test_victoria_park_head(write):
    data = read_gtsam2d(write(VICTORIA_PARK_HEAD))
    assert data.pose_ids.tolist() == [0, 1, 2, 3, 4, 6, 7, 8, 10, 11]  # ids 5 and 9 are landmarks
    assert data.landmark_ids.tolist() == [5, 9]
    assert len(data.edge_first) == 9 and len(data.reading_pose) == 3
    assert data.edge_lines.tolist() == [1, 2, 3, 4, 6, 7, 8, 10, 11]
    assert data.reading_lines.tolist() == [5, 9, 12]
    # NoiseFormatCOV: the six values are the covariance's upper triangle, here diag(1e-4, 4e-6, 4e-6).
    np.testing.assert_array_equal(data.edge_covariance[0], np.diag([1e-4, 4e-6, 4e-6]))
    # LANDMARK (x, y) becomes range |(x, y)| and bearing atan2(y, x), sigmas sqrt(v1) m and sqrt(v1 / 10) rad.
    np.testing.assert_allclose(data.reading[0], [math.hypot(11.5387, -3.2007), math.atan2(-3.2007, 11.5387)])
    np.testing.assert_allclose(data.reading_covariance[0], np.diag([0.4, 0.04]))
    assert data.reading_pose.tolist() == [4, 7, 9]  # pose indices of ids 4, 8 and 11
    assert data.reading_landmark.tolist() == [0, 1, 0]
    np.testing.assert_array_equal(data.readings_at(9), [2])
    # Initial values: odometry composed from the origin; a landmark placed from the pose of its first sighting.
    expected = np.zeros(3)
    for k in range(4):
        expected = se2.compose(expected, data.edge_measured[k])
    np.testing.assert_allclose(data.poses[4], expected, atol=1e-15)
    np.testing.assert_allclose(data.poses[0], 0.0)
    np.testing.assert_allclose(data.landmarks[0], se2.compose(data.poses[4], [11.5387, -3.2007, 0.0])[:2])


def test_problem_carries_the_factors(write):
    problem = read_graph(write(VICTORIA_PARK_HEAD))  # .txt goes to the GTSAM reader
    assert len(problem.graph.between) == 9 and len(problem.graph.range_bearing) == 3
    np.testing.assert_allclose(problem.graph.between.information[0], np.diag([1e4, 2.5e5, 2.5e5]))
    np.testing.assert_allclose(problem.graph.range_bearing.information[0], np.diag([2.5, 25.0]))
    assert problem.pose_ids.tolist()[-1] == 11 and problem.landmark_ids.tolist() == [5, 9]
    # Odometry-composed poses fit the odometry exactly: only the second sightings of landmark 5 cost anything.
    errors = problem.graph.errors(problem.initial)
    np.testing.assert_allclose(errors["between"], 0.0, atol=1e-12)
    np.testing.assert_allclose(errors["range_bearing"][:2], 0.0, atol=1e-12)
    assert np.abs(errors["range_bearing"][2]).max() > 1e-3


def test_matches_gtsam_load2d(write):
    gtsam = pytest.importorskip("gtsam")
    path = write(
        VICTORIA_PARK_HEAD + "BR 11 9 0.3 14.0 0.05 0.5\nODOMETRY 11 12 0.25 0.01 0.02 1 0 0 2 0 3\n"
    )
    data = read_gtsam2d(path)
    graph, initial = gtsam.load2D(str(path))
    for k, pid in enumerate(data.pose_ids.tolist()):
        pose = initial.atPose2(pid)
        np.testing.assert_allclose([pose.x(), pose.y(), pose.theta()], data.poses[k], atol=1e-12)
    for k, lid in enumerate(data.landmark_ids.tolist()):
        np.testing.assert_allclose(initial.atPoint2(gtsam.symbol("l", lid)), data.landmarks[k], atol=1e-12)
    # Same factors and noise: the error at a perturbed point agrees (GTSAM's error is half of ours). The poses move
    # little: GTSAM's Pose2 error is the SE(2) logarithm of the residual where ours is t2v, equal to first order.
    problem = data.to_problem()
    rng = np.random.default_rng(0)
    moved = problem.initial.copy()
    moved.poses += rng.normal(scale=1e-4, size=moved.poses.shape)
    moved.landmarks += rng.normal(scale=0.3, size=moved.landmarks.shape)
    values = gtsam.Values()
    for pid, p in zip(data.pose_ids.tolist(), moved.poses, strict=True):
        values.insert(pid, gtsam.Pose2(*p))
    for lid, p in zip(data.landmark_ids.tolist(), moved.landmarks, strict=True):
        values.insert(gtsam.symbol("l", lid), p.copy())
    assert problem.graph.error(moved) == pytest.approx(2 * graph.error(values), rel=1e-6)


def test_br_lines_and_vertices(write):
    text = (
        "VERTEX_SE2 0 1.0 2.0 0.5\n"
        "VERTEX2 1 1.5 2.0 0.5\n"
        "VERTEX_XY 7 4.0 4.0\n"
        "EDGE_SE2 0 1 0.5 0.0 0.0 0.01 0 0 0.01 0 0.001\n"
        "BR 1 7 0.3 2.5 0.05 0.2\n"
        "BR 1 8 -0.2 3.0 0.05 0.2\n"
    )
    data = read_gtsam2d(write(text))
    np.testing.assert_array_equal(
        data.poses, [[1.0, 2.0, 0.5], [1.5, 2.0, 0.5]]
    )  # vertices win over odometry
    np.testing.assert_array_equal(data.landmarks[0], [4.0, 4.0])
    np.testing.assert_allclose(data.reading[0], [2.5, 0.3])
    np.testing.assert_allclose(data.reading_covariance[0], np.diag([0.2**2, 0.05**2]))
    heading = 0.5 - 0.2
    np.testing.assert_allclose(data.landmarks[1], [1.5 + 3 * math.cos(heading), 2.0 + 3 * math.sin(heading)])


def test_noise_formats(write):
    cov = "ODOMETRY 0 1 1 0 0 0.01 0 0 0.02 0 0.03\n"  # COV order: xx xy xt yy yt tt
    graph_order = "ODOMETRY 0 1 1 0 0 0.01 0 0.02 0.03 0 0\n"  # GRAPH (TORO's order): xx xy yy tt xt yt
    expected = np.diag([0.01, 0.02, 0.03])
    for text in (cov, graph_order):  # told apart by where the zeros are, as GTSAM's NoiseFormatAUTO does
        np.testing.assert_allclose(read_gtsam2d(write(text)).edge_covariance[0], expected)
    full = "ODOMETRY 0 1 1 0 0 4 1 0.5 3 0.25 2\n"
    upper = np.array([[4, 1, 0.5], [1, 3, 0.25], [0.5, 0.25, 2]])
    np.testing.assert_allclose(read_gtsam2d(write(full), "cov").edge_covariance[0], upper)
    np.testing.assert_allclose(read_gtsam2d(write(full), "g2o").edge_covariance[0], np.linalg.inv(upper))
    toro = "ODOMETRY 0 1 1 0 0 4 1 3 2 0.5 0.25\n"
    np.testing.assert_allclose(read_gtsam2d(write(toro), "toro").edge_covariance[0], np.linalg.inv(upper))
    with pytest.raises(ValueError, match=r"graph.txt:1: cannot tell the layout"):
        read_gtsam2d(write(full))
    with pytest.raises(ValueError, match="unknown noise_format"):
        read_gtsam2d(write(cov), "information")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "ODOMETRY 0 1 0.1 0 0 0.0001 0 0 4e-06\n",
            "victoria_park.txt:1: ODOMETRY line needs 11 values, got 9",
        ),
        ("LANDMARK 4 5 11.5 -3.2 0.4 0\n", ":1: LANDMARK line needs 7 values, got 6"),
        ("VERTEX_SE2 0 0 0 0\nPOINT 1 2 3\n", ":2: unknown tag 'POINT'"),
        ("ODOMETRY a 1 0.1 0 0 1 0 0 1 0 1\n", ":1: ODOMETRY ids must be integers"),
        ("BR -1 2 0.1 1.0 0.1 0.1\n", ":1: BR ids must be non-negative"),
        ("ODOMETRY 0 1 0.1 nan 0 1 0 0 1 0 1\n", ":1: ODOMETRY has a non-finite value"),
        ("ODOMETRY 0 1 0.1 x 0 1 0 0 1 0 1\n", ":1: malformed ODOMETRY line"),
        ("VERTEX2 3 0 0 0\n\nVERTEX_SE2 3 1 1 1\n", ":3: pose 3 defined twice"),
        ("ODOMETRY 2 2 0.1 0 0 1 0 0 1 0 1\n", ":1: ODOMETRY from pose 2 to itself"),
        ("ODOMETRY 0 1 0.1 0 0 0 0 0 1 0 1\n", ":1: cannot tell the layout"),
        ("BR 0 1 0.1 1.0 0 0.1\n", ":1: BR standard deviations must be positive"),
        ("LANDMARK 0 1 1.0 1.0 0 0 0\n", ":1: LANDMARK variance must be positive"),
        ("# nothing but a comment\n", "victoria_park.txt: no poses"),
    ],
)
def test_errors_name_file_and_line(write, text, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        read_gtsam2d(write(text, "victoria_park.txt"))


def test_anisotropic_landmark_covariance_falls_back_to_unit_sigmas(write):
    with pytest.warns(UserWarning, match="not isotropic"):
        data = read_gtsam2d(write("LANDMARK 0 1 3.0 4.0 0.4 0 0.9\n"))
    np.testing.assert_allclose(data.reading_covariance[0], np.eye(2))
    np.testing.assert_allclose(data.reading[0], [5.0, math.atan2(4.0, 3.0)])
