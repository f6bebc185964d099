"""EKF-SLAM: equivalence with the textbook dense form, exact log det bookkeeping, consistency, loop closure."""

import pickle

import numpy as np
import pytest
from scipy import stats

from ekfslam_gym.filter import COURSE_SETTINGS, EKFSLAM, FilterDivergedError, range_bearing, wrap_angle
from ekfslam_gym.filter.models import odometry_motion, velocity_motion
from tests.drives import loop_drive, ring_landmarks

CONTROL_COV = np.diag([2e-4, 1e-3, 2e-4])
MEASUREMENT_COV = np.diag([0.01, 0.002])


def make_filter(n, **kwargs):
    defaults = dict(measurement_noise=MEASUREMENT_COV, pose_prior=1e-6, initial_pose=[0.0, -4.0, 0.0])
    defaults.update(kwargs)
    return EKFSLAM(n, COURSE_SETTINGS, **defaults)


def log_det_tolerance(reference):
    return 1e-8 * max(1.0, abs(reference))


def check_bookkeeping(ekf):
    sign, reference = np.linalg.slogdet(ekf.cov)
    assert sign > 0
    assert abs(ekf.log_det - reference) <= log_det_tolerance(reference)
    conditioned = np.linalg.inv(np.linalg.inv(ekf.cov)[:3, :3])
    np.testing.assert_allclose(ekf.pose_cov_given_map, conditioned, rtol=1e-7, atol=1e-12)


@pytest.mark.parametrize("init_mode", ["course", "inverse"])
@pytest.mark.parametrize("update", ["batch", "sequential"])
def test_incremental_log_det_matches_slogdet_every_step(init_mode, update):
    rng = np.random.default_rng(11)
    landmarks = ring_landmarks(12)
    drive = loop_drive(rng, 160, landmarks, CONTROL_COV, MEASUREMENT_COV)
    ekf = make_filter(12, init_mode=init_mode, update=update, resync_every=0, landmark_prior=50.0,
                      initial_pose=drive.true_poses[0])  # fmt: skip
    check_bookkeeping(ekf)
    for control, (ids, z) in zip(drive.controls, drive.readings):
        ekf.predict(control, control_cov=CONTROL_COV)
        check_bookkeeping(ekf)
        ekf.correct(ids, z)
        check_bookkeeping(ekf)
    assert ekf.observed.sum() == 12


def test_log_det_starts_once_sigma_is_definite_with_the_course_zero_pose_prior():
    ekf = EKFSLAM(3, COURSE_SETTINGS)  # course: pose covariance 0, landmarks 1000 I
    assert ekf.log_det == -np.inf
    ekf.predict([0.1, 0.2, 0.0])
    check_bookkeeping(ekf)


def test_velocity_model_bookkeeping_and_prediction():
    ekf = make_filter(4, motion_model="velocity", dt=0.1, resync_every=0, init_mode="inverse")
    ekf.correct([0, 1], [[2.0, 0.5], [3.0, -0.4]])
    for omega in (0.0, 0.3, -1.0):
        before = ekf.pose.copy()
        ekf.predict([0.5, omega], control_cov=np.diag([0.01, 0.02]))
        expected, _, _ = velocity_motion(before, 0.5, omega, 0.1)
        np.testing.assert_allclose(ekf.pose, expected)
        check_bookkeeping(ekf)


def dense_textbook_step(mean, cov, control, R, ids, z, Q):
    """The seed's full-matrix EKF-SLAM step: dense G and H, K = Sigma H^T S^-1, (I - K H) Sigma."""
    n = mean.size
    pose, G3, _ = odometry_motion(mean[:3], *control)
    G = np.eye(n)
    G[:3, :3] = G3
    Fx = np.zeros((3, n))
    Fx[:, :3] = np.eye(3)
    mean = mean.copy()
    mean[:3] = pose
    cov = G @ cov @ G.T + Fx.T @ R @ Fx
    H = np.zeros((2 * len(ids), n))
    innovation = np.zeros(2 * len(ids))
    for a, (j, zj) in enumerate(zip(ids, z)):
        zhat, Hx, Hm = range_bearing(mean[:3], mean[3 + 2 * j : 5 + 2 * j], 1e-3)
        H[2 * a : 2 * a + 2, :3] = Hx
        H[2 * a : 2 * a + 2, 3 + 2 * j : 5 + 2 * j] = Hm
        innovation[2 * a] = zj[0] - zhat[0]
        innovation[2 * a + 1] = wrap_angle(zj[1] - zhat[1])
    S = H @ cov @ H.T + np.kron(np.eye(len(ids)), Q)
    K = cov @ H.T @ np.linalg.inv(S)
    mean = mean + K @ innovation
    mean[2] = wrap_angle(mean[2])
    cov = (np.eye(n) - K @ H) @ cov
    return mean, cov


def test_fast_step_equals_the_dense_textbook_form():
    rng = np.random.default_rng(5)
    ekf = make_filter(6, init_mode="inverse", motion_noise=np.diag([0.01, 0.02, 0.003]))
    ekf.correct(np.arange(6), np.column_stack([rng.uniform(1, 4, 6), rng.uniform(-3, 3, 6)]))
    for _ in range(5):
        control = rng.normal(0, 0.3, 3)
        ids = rng.choice(6, size=4, replace=False)
        z = np.column_stack([rng.uniform(1, 4, 4), rng.uniform(-3.1, 3.1, 4)])
        mean, cov = dense_textbook_step(ekf.mean, ekf.cov, control, ekf.motion_noise, ids, z, MEASUREMENT_COV)
        ekf.predict(control)
        ekf.correct(ids, z)
        np.testing.assert_allclose(ekf.mean, mean, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(ekf.cov, cov, rtol=1e-9, atol=1e-9)


def test_covariance_stays_exactly_symmetric_and_positive_definite():
    rng = np.random.default_rng(2)
    drive = loop_drive(rng, 1500, ring_landmarks(16), CONTROL_COV, MEASUREMENT_COV)
    ekf = make_filter(16, init_mode="inverse", initial_pose=drive.true_poses[0])
    for control, (ids, z) in zip(drive.controls, drive.readings):
        ekf.predict(control, control_cov=CONTROL_COV)
        ekf.correct(ids, z)
    cov = ekf.cov
    assert np.array_equal(cov, cov.T)
    assert np.linalg.eigvalsh(cov).min() > 0
    assert np.all(np.isfinite(ekf.mean))


@pytest.mark.parametrize("update", ["batch", "sequential"])
def test_pose_anees_is_inside_chi_square_bounds(update):
    """Seeded Monte Carlo: 50 drives whose noise is what the filter models; pose NEES ~ chi2(3).

    The noise is moderate on purpose: with 15 % odometry noise per step the EKF's linearisation makes it
    over-confident (ANEES about 3.5, the known EKF-SLAM inconsistency), which is the filter's nature, not a bug.
    """
    runs, steps = 50, 150
    control_cov, measurement_cov = np.diag([2e-5, 1e-4, 2e-5]), np.diag([0.0025, 0.0004])
    landmarks = ring_landmarks(12)
    nees = np.zeros((runs, steps))
    for run in range(runs):
        rng = np.random.default_rng(1000 + run)
        drive = loop_drive(rng, steps, landmarks, control_cov, measurement_cov)
        ekf = make_filter(12, init_mode="inverse", update=update, initial_pose=drive.true_poses[0],
                          measurement_noise=measurement_cov)  # fmt: skip
        for t, (control, (ids, z)) in enumerate(zip(drive.controls, drive.readings)):
            ekf.predict(control, control_cov=control_cov)
            ekf.correct(ids, z)
            error = drive.true_poses[t + 1] - ekf.pose
            error[2] = wrap_angle(error[2])
            nees[run, t] = error @ np.linalg.solve(ekf.pose_cov, error)
    anees = nees.mean(axis=0)
    low, high = stats.chi2.ppf([0.025, 0.975], 3 * runs) / runs
    inside = np.mean((anees >= low) & (anees <= high))
    assert inside >= 0.85, f"only {inside:.0%} of steps inside [{low:.2f}, {high:.2f}]"
    assert 2.7 <= anees.mean() <= 3.3


def test_reobserving_an_early_landmark_after_a_loop_shrinks_the_pose_covariance():
    """Seed 000's loop closure: the old, certain landmark does far more than the recently seen ones."""
    rng = np.random.default_rng(7)
    landmarks = ring_landmarks(12)
    drive = loop_drive(rng, 200, landmarks, CONTROL_COV * 4, MEASUREMENT_COV, max_range=2.0)
    ekf = make_filter(12, init_mode="inverse", initial_pose=drive.true_poses[0])
    first = drive.readings[0][0]
    assert first.size
    old = int(first[0])
    last_seen, closure_step = 0, None
    for t, (control, (ids, z)) in enumerate(zip(drive.controls, drive.readings)):
        ekf.predict(control, control_cov=CONTROL_COV * 4)
        if old in ids and t - last_seen >= 50:
            closure_step = t
            without = ekf.copy()
            keep = ids != old
            without.correct(ids[keep], z[keep])
            ekf.correct(ids, z)
            break
        if old in ids:
            last_seen = t
        ekf.correct(ids, z)
    assert closure_step is not None, "the drive never came back to the first landmark"
    shrink_with = np.trace(ekf.pose_cov[:2, :2])
    shrink_without = np.trace(without.pose_cov[:2, :2])
    assert shrink_with < 0.7 * shrink_without


def test_inverse_initialisation_does_not_reuse_the_reading_and_course_does():
    for mode, expect_used_twice in (("course", True), ("inverse", False)):
        ekf = make_filter(1, init_mode=mode, pose_prior=0.01)
        before = ekf.pose_cov.copy()
        ekf.correct([0], [[2.0, 0.3]])
        changed = not np.allclose(ekf.pose_cov, before)
        assert changed == expect_used_twice


def test_bad_input_raises_and_changes_nothing():
    ekf = make_filter(3, init_mode="inverse")
    ekf.correct([0], [[1.0, 0.0]])
    mean, cov, log_det = ekf.mean.copy(), ekf.cov.copy(), ekf.log_det
    bad_calls = [
        lambda: ekf.correct([3], [[1.0, 0.0]]),
        lambda: ekf.correct([-1], [[1.0, 0.0]]),
        lambda: ekf.correct([0, 1], [[1.0, 0.0]]),
        lambda: ekf.correct([1], [[np.nan, 0.0]]),
        lambda: ekf.predict([0.1, 0.2]),
        lambda: ekf.predict([0.1, np.inf, 0.0]),
        lambda: ekf.predict([0.1, 0.1, 0.0], control_cov=np.eye(2)),
        lambda: ekf.predict([0.1, 0.1, 0.0], motion_cov=np.full((3, 3), np.nan)),
    ]
    for call in bad_calls:
        with pytest.raises(ValueError):
            call()
        assert np.array_equal(ekf.mean, mean) and np.array_equal(ekf.cov, cov) and ekf.log_det == log_det


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(n_landmarks=-1),
        dict(n_landmarks=2.5),
        dict(motion_model="ackermann"),
        dict(init_mode="delayed"),
        dict(update="parallel"),
        dict(landmark_prior=np.inf),
        dict(measurement_noise=np.array([[1.0, 2.0], [2.0, 1.0]])),
        dict(pose_prior=np.ones(4)),
        dict(initial_pose=[0.0, np.nan, 0.0]),
    ],
)
def test_bad_configuration_raises(kwargs):
    kwargs = {"n_landmarks": 2, **kwargs}
    with pytest.raises(ValueError):
        EKFSLAM(**kwargs)


def test_state_is_read_only_from_outside():
    ekf = make_filter(2)
    with pytest.raises(ValueError):
        ekf.cov[0, 0] = 1.0
    with pytest.raises(ValueError):
        ekf.mean[0] = 1.0


def test_pickle_and_copy_continue_identically():
    rng = np.random.default_rng(4)
    drive = loop_drive(rng, 40, ring_landmarks(8), CONTROL_COV, MEASUREMENT_COV)
    ekf = make_filter(8, initial_pose=drive.true_poses[0])
    for control, (ids, z) in list(zip(drive.controls, drive.readings))[:20]:
        ekf.predict(control)
        ekf.correct(ids, z)
    clones = [pickle.loads(pickle.dumps(ekf)), ekf.copy()]
    for control, (ids, z) in list(zip(drive.controls, drive.readings))[20:]:
        for f in [ekf, *clones]:
            f.predict(control)
            f.correct(ids, z)
    for clone in clones:
        assert np.array_equal(clone.mean, ekf.mean) and np.array_equal(clone.cov, ekf.cov)
        assert clone.log_det == ekf.log_det


def test_resync_reports_and_removes_drift():
    ekf = make_filter(3)
    ekf._log_det += 1e-3
    assert ekf.resync() == pytest.approx(-1e-3)
    check_bookkeeping(ekf)


def test_loss_of_definiteness_is_reported_as_divergence():
    ekf = make_filter(2, init_mode="inverse")
    ekf.correct([0], [[2.0, 0.1]])
    ekf._cov[:] = -np.eye(ekf.state_size)
    with pytest.raises(FilterDivergedError):
        ekf.correct([0], [[2.0, 0.1]])


@pytest.mark.parametrize("resync_every", [1000, 7])  # 7: resyncs fall between prediction and correction
@pytest.mark.parametrize("variant", ["ekf", "fej", "iekf"])
def test_update_is_predict_then_correct_bitwise(variant, resync_every):
    rng = np.random.default_rng(5)
    landmarks = ring_landmarks(10)
    drive = loop_drive(rng, 80, landmarks, CONTROL_COV, MEASUREMENT_COV)
    one = make_filter(10, variant=variant, initial_pose=drive.true_poses[0], resync_every=resync_every)
    two = make_filter(10, variant=variant, initial_pose=drive.true_poses[0], resync_every=resync_every)
    for control, (ids, z) in zip(drive.controls, drive.readings):
        ids = np.ascontiguousarray(ids, dtype=np.int64)
        z = np.ascontiguousarray(z, dtype=np.float64).reshape(-1, 2)
        control = np.asarray(control, dtype=np.float64)
        expected = one.predict(control, control_cov=CONTROL_COV) + one.correct(ids, z)
        assert two.update(control, CONTROL_COV, ids, z) == expected
        np.testing.assert_array_equal(two.mean, one.mean)
        np.testing.assert_array_equal(two.cov, one.cov)
        assert two.log_det == one.log_det
    check_bookkeeping(two)


def test_update_refuses_arrays_it_would_have_to_convert():
    ekf = make_filter(3)
    control = np.zeros(3)
    ids = np.array([0], dtype=np.int64)
    z = np.array([[1.0, 0.0]])
    for bad in (
        (control.astype(np.float32), CONTROL_COV, ids, z),
        (control, CONTROL_COV[:2, :2], ids, z),
        (control, CONTROL_COV, ids.astype(np.int32), z),
        (control, CONTROL_COV, ids, z[:, :1]),
        (control, np.asfortranarray(CONTROL_COV + np.eye(3) * 0.0)[:, ::-1], ids, z),
    ):
        with pytest.raises(TypeError):
            ekf.update(*bad)
    with pytest.raises(ValueError, match="landmark ids"):
        ekf.update(control, CONTROL_COV, np.array([7], dtype=np.int64), z)  # no such landmark


@pytest.mark.parametrize("update", ["batch", "sequential"])
def test_a_failed_update_leaves_a_course_initialised_landmark_as_it_was(update):
    """Course initialisation moves a landmark's mean before the update that uses its reading; when that update
    fails (an innovation covariance not positive definite) the landmark is put back: unseen, mean 0."""
    ekf = make_filter(3, init_mode="course", update=update, pose_prior=0.01)
    ekf.correct([0], [[2.0, 0.3]])
    before = (
        ekf.mean.copy(),
        ekf.cov.copy(),
        ekf.observed.copy(),
        ekf.log_det,
        ekf.pose_cov_given_map.copy(),
    )
    with pytest.raises(FilterDivergedError):
        ekf.correct([1, 2], [[3.0, -0.5], [2.5, 1.0]], measurement_cov=-1e7 * np.eye(2))
    after = (ekf.mean, ekf.cov, ekf.observed, ekf.log_det, ekf.pose_cov_given_map)
    for was, now in zip(before, after):
        assert np.array_equal(was, now)
    # and it goes on as a filter that never saw the failed call
    fresh = make_filter(3, init_mode="course", update=update, pose_prior=0.01)
    fresh.correct([0], [[2.0, 0.3]])
    for f in (ekf, fresh):
        f.correct([1, 2], [[3.0, -0.5], [2.5, 1.0]])
    assert np.array_equal(ekf.mean, fresh.mean) and np.array_equal(ekf.cov, fresh.cov)
    assert ekf.log_det == fresh.log_det


@pytest.mark.parametrize("motion_model", ["wheels", "odometry"])
def test_running_log_det_and_pose_given_map_hold_over_a_long_drive_without_resync(motion_model):
    """The default pose prior (1e-10) starts P's information near 1e10, and P is then kept by 3x3 inverses of
    it at every correction: over 1500 steps of driving, with stretches of standing still (nothing but the
    odometer's noise to move P off its prior), with no resynchronisation, the running log det and P still
    match a direct computation at the bookkeeping tests' tolerance."""
    from ekfslam_gym.sim import World, make_layout
    from ekfslam_gym.sim.sensor import SensorParams

    sensor = SensorParams()
    rng = np.random.default_rng(8)
    layout = make_layout("arena", rng, 30, width=20.0, height=20.0)
    world = World(layout, sensor=sensor)
    ekf = EKFSLAM(layout.n_landmarks, motion_model=motion_model, resync_every=0, measurement_noise=sensor.cov,
                  initial_pose=layout.start, min_range=sensor.min_range,
                  wheel_base=world.wheel_noise.wheel_base)  # fmt: skip
    assert ekf.pose_cov[0, 0] == 1e-10
    read = world.wheel_odometry if motion_model == "wheels" else world.odometry
    readings = world.sense(rng)
    ekf.correct(readings.ids, readings.z)
    for t in range(1500):
        still = t < 100 or 700 <= t < 800
        world.step(*((0.0, 0.0) if still else (rng.uniform(0.0, 1.0), rng.uniform(-2.0, 2.0))))
        odometry = read(rng)
        readings = world.sense(rng)
        ekf.predict(odometry.u, control_cov=odometry.cov)
        ekf.correct(readings.ids, readings.z)
        if t % 50 == 0 or t == 1499:
            check_bookkeeping(ekf)
    assert ekf.observed.sum() > 20


def _fails_after_one_reading(call):
    """A sequential correction whose first reading is applied and whose second fails, with log det checked
    against slogdet right after the failure.

    The first reading, at 1e308 m (finite, so it passes the input check), course-initialises a landmark so far
    away that its expected range overflows: its update still applies (it reads the heading alone, a finite,
    definite Sigma) but leaves the mean NaN, so the second reading's innovation covariance is NaN and the
    correction fails there. ``call(ekf, ids, readings)`` runs the correction."""
    ekf = make_filter(3, init_mode="course", update="sequential", pose_prior=0.01, resync_every=0)
    ekf.correct([0], [[2.0, 0.3]])
    before = ekf.log_det
    with pytest.raises(FilterDivergedError):
        call(ekf, np.array([1, 0], dtype=np.int64), np.array([[1e308, 0.5], [2.0, 0.2]]))
    assert ekf.observed[1] and not np.all(np.isfinite(ekf.mean))  # the first reading was applied
    sign, exact = np.linalg.slogdet(ekf.cov)
    assert sign > 0 and exact < before - 0.1  # it moved Sigma: the heading became better known
    assert abs(ekf.log_det - exact) <= log_det_tolerance(exact)
    conditioned = np.linalg.inv(np.linalg.inv(ekf.cov)[:3, :3])
    np.testing.assert_allclose(ekf.pose_cov_given_map, conditioned, rtol=1e-7, atol=1e-12)


def test_log_det_counts_the_readings_a_failed_sequential_correction_applied():
    _fails_after_one_reading(lambda ekf, ids, z: ekf.correct(ids, z))


def test_log_det_counts_the_readings_a_failed_sequential_update_applied():
    def update(ekf, ids, z):  # the env's path: prediction and correction in one kernel call
        ekf.update(np.zeros(3), 1e-6 * np.eye(3), ids, z)

    _fails_after_one_reading(update)


def test_log_det_counts_the_readings_a_failed_unknown_correction_applied():
    from ekfslam_gym.filter import AssociationSettings

    # jcbc matches the 2 m reading to landmark 0 and starts a new landmark for the far one in slot 1
    _fails_after_one_reading(lambda ekf, ids, z: ekf.correct_unknown(z, AssociationSettings("jcbc")))
