"""The filter's variants (FEJ, iterated) and the wheels motion model: the same exact bookkeeping as the EKF, the
Jacobians each variant claims to use (dense references), and what each is for: FEJ keeps the three unobservable
directions of planar SLAM, the iterated correction reaches the MAP of one update."""

import math

import numpy as np
import pytest

from ekfslam_gym.filter import EKFSLAM, range_bearing, wrap_angle
from ekfslam_gym.filter.models import odometry_motion, wheel_motion
from tests.drives import loop_drive, ring_landmarks

from .test_ekf import CONTROL_COV, MEASUREMENT_COV, check_bookkeeping, make_filter

VARIANTS = ("ekf", "fej", "iekf")
J = np.array([[0.0, -1.0], [1.0, 0.0]])


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("init_mode", ["course", "inverse"])
@pytest.mark.parametrize("update", ["batch", "sequential"])
def test_running_log_det_matches_slogdet_every_step(variant, init_mode, update):
    rng = np.random.default_rng(21)
    drive = loop_drive(rng, 120, ring_landmarks(10), CONTROL_COV * 4, MEASUREMENT_COV)
    ekf = make_filter(10, variant=variant, init_mode=init_mode, update=update, resync_every=0,
                      landmark_prior=50.0, initial_pose=drive.true_poses[0])  # fmt: skip
    check_bookkeeping(ekf)
    for control, (ids, z) in zip(drive.controls, drive.readings):
        ekf.predict(control, control_cov=CONTROL_COV * 4)
        check_bookkeeping(ekf)
        ekf.correct(ids, z)
        check_bookkeeping(ekf)
    assert ekf.observed.all()


@pytest.mark.parametrize("variant", VARIANTS)
def test_wheels_model_bookkeeping_and_prediction(variant):
    base = 0.3
    ekf = make_filter(4, motion_model="wheels", wheel_base=base, variant=variant, resync_every=0,
                      init_mode="inverse")  # fmt: skip
    ekf.correct([0, 1], [[2.0, 0.5], [3.0, -0.4]])
    for control in ([0.05, 0.05, 0.0], [-0.015, 0.015, 0.0], [0.03, 0.06, 0.01], [-0.04, -0.03, -0.002]):
        before = ekf.pose.copy()
        ekf.predict(control, control_cov=np.diag([1e-6, 2e-6, 4e-6]))
        expected, G, _ = wheel_motion(before, *control, base)
        np.testing.assert_allclose(ekf.pose, expected)
        if variant != "fej":
            np.testing.assert_allclose(ekf.last_jacobians.motion, G)
        check_bookkeeping(ekf)
        ekf.correct([0, 1], [[2.0, 0.5], [3.0, -0.4]])
        check_bookkeeping(ekf)


def dense_predict(mean, cov, control, R, prior_pose=None):
    """Dense EKF prediction; with ``prior_pose`` FEJ's G, whose heading column is J (p_{k+1|k} - p_{k|k-1})."""
    n = mean.size
    pose, G3, _ = odometry_motion(mean[:3], *control)
    if prior_pose is not None:
        G3 = G3.copy()
        G3[:2, 2] = J @ (pose[:2] - prior_pose[:2])
    G = np.eye(n)
    G[:3, :3] = G3
    mean = mean.copy()
    mean[:3] = pose
    cov = G @ cov @ G.T
    cov[:3, :3] += R
    return mean, cov


def dense_jacobian(n, j, Hx, Hm):
    H = np.zeros((2, n))
    H[:, :3] = Hx
    H[:, 3 + 2 * j : 5 + 2 * j] = Hm
    return H


def dense_fej_correct(mean, cov, ids, z, Q, prior_pose, first):
    """Dense FEJ correction: innovation at the current mean, H at the pose's prediction and the landmarks' first
    estimates."""
    n = mean.size
    rows, innovation = [], []
    for j, zj in zip(ids, z):
        zhat, _, _ = range_bearing(mean[:3], mean[3 + 2 * j : 5 + 2 * j], 1e-3)
        _, Hx, Hm = range_bearing(prior_pose, first[j], 1e-3)
        rows.append(dense_jacobian(n, j, Hx, Hm))
        innovation += [zj[0] - zhat[0], wrap_angle(zj[1] - zhat[1])]
    H = np.vstack(rows)
    K = cov @ H.T @ np.linalg.inv(H @ cov @ H.T + np.kron(np.eye(len(ids)), Q))
    mean = mean + K @ np.array(innovation)
    mean[2] = wrap_angle(mean[2])
    return mean, (np.eye(n) - K @ H) @ cov


def dense_iterated_correct(mean, cov, ids, z, Q, iterations, tolerance=1e-9):
    """Dense iterated EKF (Gauss-Newton on the update's MAP cost), the covariance once with the last H."""
    n = mean.size
    x = mean.copy()
    for _ in range(iterations):
        rows, innovation = [], []
        for j, zj in zip(ids, z):
            zhat, Hx, Hm = range_bearing(x[:3], x[3 + 2 * j : 5 + 2 * j], 1e-3)
            rows.append(dense_jacobian(n, j, Hx, Hm))
            innovation += [zj[0] - zhat[0], wrap_angle(zj[1] - zhat[1])]
        H = np.vstack(rows)
        K = cov @ H.T @ np.linalg.inv(H @ cov @ H.T + np.kron(np.eye(len(ids)), Q))
        new = mean + K @ (np.array(innovation) + H @ (x - mean))
        converged = np.max(np.abs(new - x)) < tolerance
        x = new
        if converged:
            break
    x[2] = wrap_angle(x[2])
    return x, (np.eye(n) - K @ H) @ cov


def _seeded_filter(variant, rng, **kwargs):
    ekf = make_filter(6, init_mode="inverse", variant=variant, motion_noise=np.diag([0.01, 0.02, 0.003]),
                      **kwargs)  # fmt: skip
    ekf.correct(np.arange(6), np.column_stack([rng.uniform(1, 4, 6), rng.uniform(-3, 3, 6)]))
    return ekf


def test_fej_step_equals_the_dense_form_with_first_estimates():
    rng = np.random.default_rng(22)
    ekf = _seeded_filter("fej", rng)
    first = ekf.landmarks.copy()  # inverse initialisation: the first estimates are the initial means
    prior = ekf.pose.copy()  # no prediction yet: the initial pose is the pose's first estimate
    mean, cov = ekf.mean.copy(), ekf.cov.copy()
    for _ in range(6):
        control = rng.normal(0, 0.3, 3)
        ids = rng.choice(6, size=4, replace=False)
        z = np.column_stack([rng.uniform(1, 4, 4), rng.uniform(-3.1, 3.1, 4)])
        mean, cov = dense_predict(mean, cov, control, ekf.motion_noise, prior_pose=prior)
        prior = mean[:3].copy()
        mean, cov = dense_fej_correct(mean, cov, ids, z, MEASUREMENT_COV, prior, first)
        ekf.predict(control)
        ekf.correct(ids, z)
        np.testing.assert_allclose(ekf.mean, mean, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(ekf.cov, cov, rtol=1e-9, atol=1e-9)
        used = ekf.last_jacobians
        np.testing.assert_array_equal(used.slots, ids)
        for j, h in zip(ids, used.measurement):
            _, Hx, Hm = range_bearing(prior, first[j], 1e-3)
            np.testing.assert_allclose(h, np.hstack([Hx, Hm]), rtol=1e-12, atol=1e-12)
    assert not np.allclose(ekf.landmarks, first)  # the estimates moved on, the Jacobians stayed


@pytest.mark.parametrize("iterations", [1, 2, 5])
def test_iterated_step_equals_the_dense_gauss_newton_form(iterations):
    rng = np.random.default_rng(23)
    ekf = _seeded_filter("iekf", rng, iterations=iterations)
    mean, cov = ekf.mean.copy(), ekf.cov.copy()
    for _ in range(6):
        control = rng.normal(0, 0.3, 3)
        ids = rng.choice(6, size=4, replace=False)
        z = np.column_stack([rng.uniform(1, 4, 4), rng.uniform(-3.1, 3.1, 4)])
        mean, cov = dense_predict(mean, cov, control, ekf.motion_noise)
        mean, cov = dense_iterated_correct(mean, cov, ids, z, MEASUREMENT_COV, iterations)
        ekf.predict(control)
        ekf.correct(ids, z)
        np.testing.assert_allclose(ekf.mean, mean, rtol=1e-8, atol=1e-8)
        np.testing.assert_allclose(ekf.cov, cov, rtol=1e-8, atol=1e-9)


def test_one_iteration_is_the_ekf_bit_for_bit():
    rng = np.random.default_rng(24)
    drive = loop_drive(rng, 60, ring_landmarks(8), CONTROL_COV, MEASUREMENT_COV)
    filters = [make_filter(8, initial_pose=drive.true_poses[0]),
               make_filter(8, initial_pose=drive.true_poses[0], variant="iekf", iterations=1)]  # fmt: skip
    for control, (ids, z) in zip(drive.controls, drive.readings):
        for f in filters:
            f.predict(control, control_cov=CONTROL_COV)
            f.correct(ids, z)
    assert np.array_equal(filters[0].mean, filters[1].mean) and np.array_equal(filters[0].cov, filters[1].cov)
    assert filters[0].log_det == filters[1].log_det


def test_iterated_correction_reaches_the_map_of_the_update():
    """With a heading uncertain by 0.3 rad and landmarks 4 m away the update is far from linear: the IEKF's
    mean is a stationary point of the update's MAP cost (its gradient vanishes), the EKF's is not."""
    rng = np.random.default_rng(25)
    means = {}
    for variant in ("ekf", "iekf"):
        ekf = make_filter(3, init_mode="inverse", variant=variant, iterations=20, initial_pose_cov=[1e-4, 1e-4, 0.09],
                          initial_pose=[0.0, 0.0, 0.0])  # fmt: skip
        ekf.correct([0, 1, 2], [[4.0, 0.0], [4.0, 2.0], [4.0, -2.0]])
        prior_mean, prior_cov = ekf.mean.copy(), ekf.cov.copy()
        truth_heading = 0.25  # the readings come from a pose turned by 0.25 rad
        ids = np.array([0, 1, 2])
        z = np.array([[4.0, -truth_heading], [4.0, 2.0 - truth_heading], [4.0, -2.0 - truth_heading]])
        z += rng.normal(0.0, 0.01, z.shape)
        ekf.correct(ids, z)
        means[variant] = ekf.mean.copy()

        def gradient(x, prior_mean=prior_mean, prior_cov=prior_cov, ids=ids, z=z):
            g = np.linalg.solve(prior_cov, x - prior_mean)
            for j, zj in zip(ids, z):
                zhat, Hx, Hm = range_bearing(x[:3], x[3 + 2 * j : 5 + 2 * j], 1e-3)
                H = dense_jacobian(x.size, j, Hx, Hm)
                r = np.array([zj[0] - zhat[0], wrap_angle(zj[1] - zhat[1])])
                g -= H.T @ np.linalg.solve(MEASUREMENT_COV, r)
            return g

        scale = np.abs(np.linalg.solve(prior_cov, prior_mean - ekf.mean)).max()
        means[variant + "_gradient"] = np.abs(gradient(ekf.mean)).max() / scale
    assert means["iekf_gradient"] < 1e-6
    assert means["ekf_gradient"] > 1e-3
    assert abs(wrap_angle(means["iekf"][2] - 0.25)) < abs(wrap_angle(means["ekf"][2] - 0.25))


def observability_matrix(variant, steps=6):
    """[H_1 Phi_1; H_2 Phi_2 Phi_1; ...] of the linearised SLAM system (Phi_t the prediction into step t, H_t
    the correction at step t), from the Jacobians the filter used (``last_jacobians``), over a few steps of a
    seeded drive that reads every landmark at every step; the first readings only initialise the landmarks.
    The columns are the state after that initialisation."""
    rng = np.random.default_rng(26)
    n = 5
    drive = loop_drive(rng, 20, ring_landmarks(n), CONTROL_COV * 25, MEASUREMENT_COV * 4, max_range=100.0)
    ekf = make_filter(n, init_mode="inverse", variant=variant, initial_pose=drive.true_poses[0])
    size = ekf.state_size
    blocks, transition = [], np.eye(size)
    for t, (control, (ids, z)) in enumerate(zip(drive.controls, drive.readings)):
        if t > 0:  # a prediction between two corrections
            ekf.predict(control, control_cov=CONTROL_COV * 25)
            phi = np.eye(size)
            phi[:3, :3] = ekf.last_jacobians.motion
            transition = phi @ transition
        ekf.correct(ids, z)
        used = ekf.last_jacobians
        if t == 0:
            assert used.slots.size == 0  # the first readings only initialised the landmarks
            continue
        for j, h in zip(used.slots, used.measurement):
            blocks.append(dense_jacobian(size, j, h[:, :3], h[:, 3:]) @ transition)
        if t == steps:
            break
    return np.vstack(blocks)


def null_space_dimension(matrix, tolerance=1e-9):
    singular = np.linalg.svd(matrix, compute_uv=False)
    return int(np.sum(singular < tolerance * singular[0])), singular


def test_fej_keeps_the_three_unobservable_directions_and_the_ekf_loses_rotation():
    """Planar SLAM cannot observe a global translation or rotation (Huang, Mourikis & Roumeliotis 2010):
    the FEJ filter's linearised system has exactly that 3-dimensional null space, the standard EKF's only the
    2 translations (it gains spurious information about the global heading). The tolerance, 1e-9 of the
    largest singular value, sits between rounding (the FEJ's three smallest, about 1e-16 of it) and the
    smallest genuine values (about 2e-2 of it here, for both)."""
    fej_dim, fej_singular = null_space_dimension(observability_matrix("fej"))
    ekf_dim, ekf_singular = null_space_dimension(observability_matrix("ekf"))
    assert fej_dim == 3, fej_singular[-5:] / fej_singular[0]
    assert ekf_dim == 2, ekf_singular[-5:] / ekf_singular[0]
    # the margins around the tolerance are wide
    assert fej_singular[-3] < 1e-13 * fej_singular[0] and fej_singular[-4] > 1e-3 * fej_singular[0]
    assert ekf_singular[-2] < 1e-13 * ekf_singular[0] and ekf_singular[-3] > 1e-3 * ekf_singular[0]


def test_fej_null_space_is_global_translation_and_rotation():
    """The FEJ null space is spanned by the global translations and the rotation about the origin, at the
    state the matrix starts from: the pose before the first prediction and the landmarks' first estimates."""
    _, _, vt = np.linalg.svd(observability_matrix("fej"))
    null = vt[-3:].T
    rng = np.random.default_rng(26)
    drive = loop_drive(rng, 20, ring_landmarks(5), CONTROL_COV * 25, MEASUREMENT_COV * 4, max_range=100.0)
    ekf = make_filter(5, init_mode="inverse", variant="fej", initial_pose=drive.true_poses[0])
    ekf.correct(*drive.readings[0])
    pose, landmarks = ekf.pose.copy(), ekf.landmarks.copy()
    translation_x = np.r_[1.0, 0.0, 0.0, np.tile([1.0, 0.0], 5)]
    translation_y = np.r_[0.0, 1.0, 0.0, np.tile([0.0, 1.0], 5)]
    rotation = np.r_[J @ pose[:2], 1.0, (landmarks @ J.T).ravel()]
    expected = np.column_stack([translation_x, translation_y, rotation])
    residual = expected - null @ (null.T @ expected)
    assert np.abs(residual).max() < 1e-8 * np.abs(expected).max()


@pytest.mark.parametrize("kwargs", [dict(variant="ukf"), dict(iterations=0), dict(iterations=True),
                                    dict(wheel_base=0.0), dict(motion_model="bicycle")])  # fmt: skip
def test_bad_variant_configuration_raises(kwargs):
    with pytest.raises(ValueError):
        EKFSLAM(2, **kwargs)


@pytest.mark.parametrize("variant", VARIANTS)
def test_variants_stay_symmetric_positive_definite_and_pickle(variant):
    import pickle

    rng = np.random.default_rng(27)
    drive = loop_drive(rng, 400, ring_landmarks(12), CONTROL_COV, MEASUREMENT_COV)
    ekf = make_filter(12, init_mode="inverse", variant=variant, initial_pose=drive.true_poses[0])
    for t, (control, (ids, z)) in enumerate(zip(drive.controls, drive.readings)):
        if t == 200:
            clone = pickle.loads(pickle.dumps(ekf))
        for f in (ekf, clone) if t >= 200 else (ekf,):
            f.predict(control, control_cov=CONTROL_COV)
            f.correct(ids, z)
    assert np.array_equal(ekf.cov, ekf.cov.T) and np.linalg.eigvalsh(ekf.cov).min() > 0
    assert np.array_equal(clone.mean, ekf.mean) and np.array_equal(clone.cov, ekf.cov)
    error = drive.true_poses[-1] - ekf.pose
    assert math.hypot(error[0], error[1]) < 0.5
