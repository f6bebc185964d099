"""Smoothing recorded drives: odometry edges with their covariance, range-bearing edges, dead-reckoning start."""

from __future__ import annotations

import numpy as np
import pytest

from ekfslam_gym.angles import wrap_angles
from ekfslam_gym.data.synthetic import synthetic_drive
from ekfslam_gym.graph import se2
from ekfslam_gym.graph.smoother import dead_reckoning, odometry_edge_covariance, smooth_drive


def ate(estimate: np.ndarray, truth: np.ndarray) -> float:
    """Absolute trajectory error: RMS position error [m], both trajectories in the same (anchored) frame."""
    return float(np.sqrt(np.mean(np.sum((estimate[:, :2] - truth[:, :2]) ** 2, axis=1))))


def landmark_rmse(estimate: np.ndarray, truth: np.ndarray) -> float:
    seen = ~np.isnan(estimate[:, 0])
    return float(np.sqrt(np.mean(np.sum((estimate[seen] - truth[seen]) ** 2, axis=1))))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_smoothing_beats_dead_reckoning(seed):
    drive = synthetic_drive(250, 25, seed=seed)
    out = smooth_drive(
        drive.true_poses[0], drive.odometry, drive.odometry_cov, drive.readings, drive.reading_cov
    )
    assert out.result.converged
    dr_ate, smoothed_ate = ate(out.dead_reckoning, drive.true_poses), ate(out.poses, drive.true_poses)
    assert smoothed_ate < 0.5 * dr_ate, (smoothed_ate, dr_ate)
    assert landmark_rmse(out.landmarks, drive.landmarks) < 0.5 * landmark_rmse(
        out.initial_landmarks, drive.landmarks
    )
    # The optimum is consistent with the noise: F ≈ χ² with (residuals − unknowns) degrees of freedom.
    residuals = 3 * (len(drive.odometry) + 1) + 2 * sum(len(r) for r in drive.readings)
    unknowns = 3 * len(out.poses) + 2 * int(np.sum(~np.isnan(out.landmarks[:, 0])))
    dof = residuals - unknowns
    assert abs(out.result.final_error - dof) < 5 * np.sqrt(2 * dof)


def test_gauss_newton_and_levenberg_marquardt_smooth_alike():
    drive = synthetic_drive(150, 15, seed=3)
    args = (drive.true_poses[0], drive.odometry, drive.odometry_cov, drive.readings, drive.reading_cov)
    gn, lm = smooth_drive(*args, method="gn"), smooth_drive(*args, method="lm")
    assert lm.result.final_error == pytest.approx(gn.result.final_error, rel=1e-7)
    np.testing.assert_allclose(lm.poses[:, :2], gn.poses[:, :2], atol=1e-5)


def test_noise_free_drive_is_recovered_exactly():
    drive = synthetic_drive(80, 10, seed=4, odometry_std=(0.0, 0.0, 0.0), reading_std=(0.0, 0.0))
    # Zero noise: pass nominal covariances to the smoother (the data is exact, so any weights give the truth).
    out = smooth_drive(
        drive.true_poses[0],
        drive.odometry,
        np.diag([1e-4, 1e-4, 1e-4]),
        drive.readings,
        np.diag([1e-2, 1e-3]),
    )
    np.testing.assert_allclose(out.dead_reckoning[:, :2], drive.true_poses[:, :2], atol=1e-9)
    np.testing.assert_allclose(out.poses[:, :2], drive.true_poses[:, :2], atol=1e-6)
    seen = ~np.isnan(out.landmarks[:, 0])
    np.testing.assert_allclose(out.landmarks[seen], drive.landmarks[seen], atol=1e-6)


def test_readings_at_the_initial_pose_unseen_landmarks_and_turning_on_the_spot():
    # Pose 0 reads landmark 2; the robot turns on the spot (t = 0), then drives; landmark 1 is never read.
    landmarks = np.array([[3.0, 1.0], [50.0, 50.0], [1.0, 2.0], [0.0, 4.0]])
    truth = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.5], [1.0, 0.5, 0.3], [2.0, 1.0, 0.6]])
    controls = []
    for a, b in zip(truth[:-1], truth[1:], strict=True):
        d = b[:2] - a[:2]
        t = np.hypot(*d)
        r1 = wrap_angles(np.arctan2(d[1], d[0]) - a[2]) if t > 0 else 0.0
        controls.append([r1, t, wrap_angles(b[2] - a[2] - r1)])

    def read(pose, ids):
        rows = []
        for i in ids:
            d = landmarks[i] - pose[:2]
            rows.append([i, np.hypot(*d), wrap_angles(np.arctan2(d[1], d[0]) - pose[2])])
        return np.array(rows)

    readings = [read(truth[0], [2]), read(truth[1], [0, 2]), [], read(truth[3], [0, 3])]
    out = smooth_drive(
        truth[0], controls, np.diag([1e-3, 1e-3, 1e-3]), readings, np.diag([1e-3, 1e-4]), num_landmarks=5
    )
    assert out.landmarks.shape == (5, 2)
    assert np.isnan(out.landmarks[[1, 4]]).all()
    np.testing.assert_allclose(out.poses, truth, atol=1e-6)
    np.testing.assert_allclose(out.landmarks[[0, 2, 3]], landmarks[[0, 2, 3]], atol=1e-6)
    with pytest.raises(ValueError, match="reading steps"):
        smooth_drive(truth[0], controls, np.eye(3), readings[:2], np.eye(2))
    with pytest.raises(ValueError, match="num_landmarks=2"):
        smooth_drive(truth[0], controls, np.eye(3), readings, np.eye(2), num_landmarks=2)


def test_no_readings_gives_dead_reckoning():
    drive = synthetic_drive(30, 5, seed=5)
    out = smooth_drive(drive.true_poses[0], drive.odometry, drive.odometry_cov, [[]] * 30, drive.reading_cov)
    np.testing.assert_allclose(out.poses, out.dead_reckoning, atol=1e-9)
    assert out.landmarks.shape == (0, 2)


def test_odometry_edge_covariance_matches_sampling():
    """The linearised V M Vᵀ (rotated into the error's frame) against Monte-Carlo errors of noisy controls."""
    rng = np.random.default_rng(6)
    u = np.array([0.3, 0.8, -0.2])
    M = np.diag([0.02, 0.01, 0.03]) ** 2
    samples = rng.multivariate_normal(u, M, size=200_000)
    z = se2.odometry_to_relative(u)
    # The edge's error at the true relative pose z: e = t2v(Z⁻¹ z) with Z the noisy measurement.
    errors = se2.between(se2.odometry_to_relative(samples), np.broadcast_to(z, samples.shape))
    cov = odometry_edge_covariance(u, M)[0]
    scale = 1.0 / np.sqrt(np.diag(cov))
    # Compared in units of the standard deviations (correlation scale): sampling error ~ 1/√n ≈ 0.002.
    np.testing.assert_allclose(
        scale[:, None] * np.cov(errors.T) * scale, scale[:, None] * cov * scale, atol=0.02
    )


def test_dead_reckoning_chains_odometry():
    poses = dead_reckoning([1.0, 2.0, np.pi - 0.1], [[0.2, 1.0, 0.0], [0.0, 0.0, 0.2]])
    np.testing.assert_allclose(poses[1], [1.0 + np.cos(np.pi + 0.1), 2.0 + np.sin(np.pi + 0.1), -np.pi + 0.1])
    np.testing.assert_allclose(poses[2, :2], poses[1, :2])
    assert poses[2, 2] == pytest.approx(-np.pi + 0.3)


WHEEL_BASE = 0.3


@pytest.mark.parametrize("u", [[0.10, 0.12, 0.0], [0.05, 0.05, 0.01], [-0.03, 0.03, 0.0], [0.2, -0.1, -0.02]])
def test_wheels_relative_pose_is_the_filters_wheel_motion(u):
    from ekfslam_gym.filter.models import wheel_motion

    pose = np.array([1.0, -2.0, 2.9])
    moved, _, V = wheel_motion(pose, *u, WHEEL_BASE)
    np.testing.assert_allclose(se2.compose(pose, se2.wheels_to_relative(u, WHEEL_BASE)), moved, atol=1e-12)
    # From the origin the pose Jacobian V of the filter's model is the relative pose's Jacobian.
    np.testing.assert_allclose(se2.wheels_jacobian(u, WHEEL_BASE), wheel_motion(np.zeros(3), *u, WHEEL_BASE)[2],
                               atol=1e-12)  # fmt: skip
    assert V.shape == (3, 3)


@pytest.mark.parametrize(
    "u", [[0.10, 0.12, 0.0], [0.04, 0.04, 0.0], [0.04, 0.04 + 1e-6, 0.003], [0.3, -0.2, 0.01]]
)
def test_wheels_jacobian_matches_finite_differences(u):
    u = np.asarray(u, dtype=float)
    J = se2.wheels_jacobian(u, WHEEL_BASE)
    h = 1e-7
    for k in range(3):
        step = np.zeros(3)
        step[k] = h
        numeric = (
            se2.wheels_to_relative(u + step, WHEEL_BASE) - se2.wheels_to_relative(u - step, WHEEL_BASE)
        ) / (2 * h)
        np.testing.assert_allclose(J[:, k], numeric, atol=1e-7)


def test_wheels_edge_covariance_matches_sampling():
    rng = np.random.default_rng(7)
    u = np.array([0.08, 0.12, 0.0])
    M = np.diag([0.004, 0.005, 0.002]) ** 2
    samples = rng.multivariate_normal(u, M, size=200_000)
    z = se2.wheels_to_relative(u, WHEEL_BASE)
    errors = se2.between(se2.wheels_to_relative(samples, WHEEL_BASE), np.broadcast_to(z, samples.shape))
    cov = odometry_edge_covariance(u, M, "wheels", WHEEL_BASE)[0]
    scale = 1.0 / np.sqrt(np.diag(cov))
    np.testing.assert_allclose(
        scale[:, None] * np.cov(errors.T) * scale, scale[:, None] * cov * scale, atol=0.02
    )


def test_the_wheels_model_needs_its_wheel_base():
    with pytest.raises(ValueError, match="wheel_base"):
        dead_reckoning([0, 0, 0], [[0.1, 0.1, 0.0]], "wheels")
    with pytest.raises(ValueError, match="motion_model"):
        dead_reckoning([0, 0, 0], [[0.1, 0.1, 0.0]], "velocity")
