"""The team filter (``TeamEKF``): the robot-to-robot model's Jacobians, one robot against ``EKFSLAM``, the exact
log det after long mixed sequences, a robot-to-robot step against the dense textbook form, and a seeded Monte
Carlo consistency check of robot-to-robot fusion."""

import math

import numpy as np
import pytest
from scipy import stats

from ekfslam_gym.filter import COURSE_SETTINGS, EKFSLAM, FilterSettings
from ekfslam_gym.filter.models import odometry_motion, range_bearing, wrap_angle
from ekfslam_gym.filter.team import TeamEKF
from ekfslam_gym.filter.team_models import robot_range_bearing

from .drives import loop_drive, ring_landmarks
from .test_models import numeric_jacobian

CONTROL_COV = np.diag([2e-4, 1e-3, 2e-4])
MEASUREMENT_COV = np.diag([0.01, 0.002])


# ------------------------------------------------------------------ the robot-to-robot model
@pytest.mark.parametrize(
    "observer, target",
    [
        ([0.3, -1.2, 0.4], [2.0, 1.0, -2.0]),
        ([2.0, 1.0, math.pi - 1e-4], [-1.0, 1.1, 0.3]),  # bearing near the wrap
        ([-1.0, 3.0, -math.pi + 1e-4], [-1.5, -2.0, math.pi]),
    ],
)
def test_robot_range_bearing_jacobians_match_finite_differences(observer, target):
    observer, target = np.array(observer), np.array(target)
    z, h_observer, h_target = robot_range_bearing(observer, target, 1e-3)
    np.testing.assert_allclose(z, range_bearing(observer, target[:2], 1e-3)[0])
    num_observer = numeric_jacobian(
        lambda p: robot_range_bearing(p, target, 1e-3)[0], observer, angle_rows=(1,)
    )
    num_target = numeric_jacobian(
        lambda p: robot_range_bearing(observer, p, 1e-3)[0], target, angle_rows=(1,)
    )
    np.testing.assert_allclose(h_observer, num_observer, atol=1e-7)
    np.testing.assert_allclose(h_target, num_target, atol=1e-7)
    assert np.all(h_target[:, 2] == 0.0)  # the target's heading is not read


# ------------------------------------------------------------------ one robot is EKFSLAM
@pytest.mark.parametrize("variant", ["ekf", "fej", "iekf"])
@pytest.mark.parametrize(
    "init_mode, update", [("course", "batch"), ("inverse", "batch"), ("inverse", "sequential")]
)
def test_one_robot_reproduces_ekfslam(variant, init_mode, update):
    rng = np.random.default_rng(5)
    landmarks = ring_landmarks(10)
    drive = loop_drive(rng, 150, landmarks, CONTROL_COV, MEASUREMENT_COV)
    kwargs = dict(
        measurement_noise=MEASUREMENT_COV, pose_prior=1e-6, variant=variant, init_mode=init_mode, update=update,
        landmark_prior=50.0, resync_every=40,
    )  # fmt: skip
    single = EKFSLAM(10, COURSE_SETTINGS, initial_pose=drive.true_poses[0], **kwargs)
    team = TeamEKF(1, 10, COURSE_SETTINGS, initial_poses=drive.true_poses[:1], **kwargs)
    for control, (ids, z) in zip(drive.controls, drive.readings):
        assert team.predict(0, control, control_cov=CONTROL_COV) == pytest.approx(
            single.predict(control, control_cov=CONTROL_COV), rel=1e-9, abs=1e-9
        )
        assert team.correct(0, ids, z) == pytest.approx(single.correct(ids, z), rel=1e-9, abs=1e-9)
    np.testing.assert_allclose(team.mean, single.mean, rtol=0, atol=1e-12)
    np.testing.assert_allclose(team.cov, single.cov, rtol=0, atol=1e-12)
    np.testing.assert_allclose(team.pose_cov_given_map, single.pose_cov_given_map, rtol=1e-9, atol=1e-15)
    assert team.log_det == pytest.approx(single.log_det, rel=1e-12, abs=1e-10)
    np.testing.assert_array_equal(team.observed, single.observed)


def test_one_robot_reproduces_ekfslam_with_the_env_defaults():
    """The env's filter (wheels model, inverse initialisation, tiny pose prior) and the velocity model."""
    rng = np.random.default_rng(8)
    for model, width in (("wheels", 3), ("velocity", 2)):
        single = EKFSLAM(6, motion_model=model)
        team = TeamEKF(1, 6, motion_model=model)
        landmark = rng.uniform(-3, 3, (6, 2))
        for _ in range(60):
            control = rng.normal(0.05, 0.02, width)
            cov = np.diag(rng.uniform(1e-5, 1e-4, width))
            single.predict(control, control_cov=cov)
            team.predict(0, control, control_cov=cov)
            ids = rng.choice(6, size=3, replace=False)
            z = np.array([range_bearing(single.pose, landmark[i], 1e-3)[0] for i in ids])
            z += rng.normal(0, 0.01, z.shape)
            single.correct(ids, z)
            team.correct(0, ids, z)
        np.testing.assert_allclose(team.mean, single.mean, rtol=0, atol=1e-12)
        np.testing.assert_allclose(team.cov, single.cov, rtol=0, atol=1e-12)
        assert team.log_det == pytest.approx(single.log_det, rel=1e-12)


# ------------------------------------------------------------------ exact log det with many robots
def check_bookkeeping(team: TeamEKF) -> None:
    sign, reference = np.linalg.slogdet(team.cov)
    assert sign > 0
    assert abs(team.log_det - reference) <= 1e-8 * max(1.0, abs(reference))
    pose_size = 3 * team.n_robots
    conditioned = np.linalg.inv(np.linalg.inv(team.cov)[:pose_size, :pose_size])
    np.testing.assert_allclose(team.pose_cov_given_map, conditioned, rtol=1e-6, atol=1e-12)


def team_world(rng, n_robots=3, n_landmarks=12):
    landmarks = ring_landmarks(n_landmarks)
    starts = np.column_stack(
        [rng.uniform(-3, 3, n_robots), rng.uniform(-3, 3, n_robots), rng.uniform(-np.pi, np.pi, n_robots)]
    )
    return landmarks, starts


def mixed_sequence(rng, team: TeamEKF, truth: np.ndarray, landmarks: np.ndarray, steps: int, check=None):
    """Random interleaving of predictions, landmark and robot-to-robot readings (noise-free readings of a
    moving truth: the bookkeeping does not need them noisy)."""
    n = team.n_robots
    for _ in range(steps):
        robot = int(rng.integers(n))
        control = np.array([rng.normal(0, 0.1), abs(rng.normal(0.2, 0.05)), rng.normal(0, 0.1)])
        truth[robot] = odometry_motion(truth[robot], *control)[0]
        team.predict(robot, control, control_cov=CONTROL_COV)
        if check:
            check(team)
        kind = rng.integers(3)
        if kind == 0:
            ids = rng.choice(len(landmarks), size=int(rng.integers(1, 4)), replace=False)
            z = np.array([range_bearing(truth[robot], landmarks[i], 1e-3)[0] for i in ids])
            team.correct(robot, ids, z)
        elif kind == 1 and n > 1:
            others = [j for j in range(n) if j != robot]
            targets = rng.choice(others, size=int(rng.integers(1, len(others) + 1)), replace=False)
            z = np.array([robot_range_bearing(truth[robot], truth[j], 1e-3)[0] for j in targets])
            team.correct_robots(robot, targets, z)
        if check:
            check(team)


@pytest.mark.parametrize("variant", ["ekf", "fej", "iekf"])
@pytest.mark.parametrize("init_mode, update", [("inverse", "batch"), ("course", "sequential")])
def test_running_log_det_matches_slogdet_over_a_long_mixed_sequence(variant, init_mode, update):
    rng = np.random.default_rng(21)
    landmarks, starts = team_world(rng)
    team = TeamEKF(
        3, len(landmarks), COURSE_SETTINGS, initial_poses=starts, measurement_noise=MEASUREMENT_COV,
        pose_prior=1e-4, variant=variant, init_mode=init_mode, update=update, landmark_prior=50.0,
        resync_every=0,
    )  # fmt: skip
    check_bookkeeping(team)
    mixed_sequence(rng, team, starts.copy(), landmarks, 120, check=check_bookkeeping)
    mixed_sequence(rng, team, team.poses.copy(), landmarks, 400)  # long, then checked once
    check_bookkeeping(team)
    assert team.observed.all()


def test_resync_finds_no_drift_and_course_zero_prior_starts_tracking():
    rng = np.random.default_rng(3)
    landmarks, starts = team_world(rng, n_robots=2, n_landmarks=6)
    team = TeamEKF(2, 6, COURSE_SETTINGS, initial_poses=starts, measurement_noise=MEASUREMENT_COV)
    assert team.log_det == -np.inf  # zero pose prior: Sigma singular
    team.predict(0, [0.1, 0.2, 0.0], control_cov=CONTROL_COV)
    assert team.log_det == -np.inf  # robot 1 still exact
    team.predict(1, [0.1, 0.2, 0.0], control_cov=CONTROL_COV)
    assert np.isfinite(team.log_det)
    mixed_sequence(rng, team, team.poses.copy(), landmarks, 200)
    before = team.log_det
    assert abs(team.resync()) <= 1e-8 * max(1.0, abs(before))


# ------------------------------------------------------------------ a robot-to-robot step is the textbook EKF's
def dense_robot_correct(mean, cov, observer, targets, z, Q, variant, prior_poses, iterations=5):
    """The textbook EKF (full H), FEJ (H at the predicted poses) or Gauss-Newton IEKF correction with robot
    ``observer``'s readings of robots ``targets``."""
    size = len(mean)
    x = mean.copy()
    rounds = iterations if variant == "iekf" else 1
    for _ in range(rounds):
        H = np.zeros((2 * len(targets), size))
        nu = np.zeros(2 * len(targets))
        o = 3 * observer
        for a, j in enumerate(targets):
            t = 3 * j
            zj, _, _ = robot_range_bearing(mean[o : o + 3], mean[t : t + 3], 1e-3)
            if variant == "fej":
                _, h_observer, h_target = robot_range_bearing(prior_poses[observer], prior_poses[j], 1e-3)
            else:
                zj, h_observer, h_target = robot_range_bearing(x[o : o + 3], x[t : t + 3], 1e-3)
            H[2 * a : 2 * a + 2, o : o + 3] = h_observer
            H[2 * a : 2 * a + 2, t : t + 3] = h_target
            nu[2 * a : 2 * a + 2] = z[a] - zj
        nu[1::2] = [wrap_angle(v) for v in nu[1::2]]
        S = H @ cov @ H.T + np.kron(np.eye(len(targets)), Q)
        K = cov @ H.T @ np.linalg.inv(S)
        new = mean + K @ (nu + H @ (x - mean))
        converged = np.max(np.abs(new - x)) < 1e-9
        x = new
        if converged:
            break
    return x, (np.eye(size) - K @ H) @ cov, S, nu


@pytest.mark.parametrize("variant", ["ekf", "fej", "iekf"])
def test_robot_reading_equals_the_dense_textbook_update(variant):
    rng = np.random.default_rng(4)
    landmarks, starts = team_world(rng, n_robots=3, n_landmarks=5)
    team = TeamEKF(
        3, 5, initial_poses=starts, measurement_noise=MEASUREMENT_COV, pose_prior=1e-3, variant=variant
    )
    mixed_sequence(rng, team, starts.copy(), landmarks, 30)
    mean, cov, prior_poses = team.mean.copy(), team.cov.copy(), team._prior_poses.copy()
    z = np.array([[2.5, 0.3], [1.7, -1.0]])
    targets = np.array([0, 2])
    observer = 1
    dense_mean, dense_cov, S, nu = dense_robot_correct(
        mean, cov, observer, targets, z, MEASUREMENT_COV, variant, prior_poses
    )
    delta = team.correct_robots(observer, targets, z)
    np.testing.assert_allclose(team.cov, dense_cov, atol=1e-10)
    np.testing.assert_allclose(team.mean[[0, 1, 3, 4, 6, 7]], dense_mean[[0, 1, 3, 4, 6, 7]], atol=1e-9)
    headings = team.mean[[2, 5, 8]] - dense_mean[[2, 5, 8]]
    np.testing.assert_allclose([wrap_angle(h) for h in headings], 0.0, atol=1e-9)
    assert delta == pytest.approx(
        2 * np.linalg.slogdet(MEASUREMENT_COV)[1] - np.linalg.slogdet(S)[1], abs=1e-9
    )
    if variant != "ekf":
        return
    # NIS of the readings before the update, per reading, from the same S blocks
    check = TeamEKF(3, 5, initial_poses=starts, measurement_noise=MEASUREMENT_COV, pose_prior=1e-3)
    check._mean[:], check._cov[:, :] = mean, cov
    nis = check.reading_nis(observer, z, robots=targets)
    for a in range(2):
        block = S[2 * a : 2 * a + 2, 2 * a : 2 * a + 2]
        v = nu[2 * a : 2 * a + 2]
        assert nis[a] == pytest.approx(v @ np.linalg.solve(block, v), rel=1e-9)


def test_bad_input_names_what_is_wrong():
    team = TeamEKF(2, 3)
    with pytest.raises(IndexError, match="robot index 2"):
        team.predict(2, [0.1, 0.1, 0.0])
    with pytest.raises(ValueError, match="other than the observer 0"):
        team.correct_robots(0, [0], [[1.0, 0.0]])
    with pytest.raises(ValueError, match=r"landmark ids must lie in \[0, 3\)"):
        team.correct(1, [3], [[1.0, 0.0]])
    with pytest.raises(ValueError, match="1 ids but 2 readings"):
        team.correct(1, [0], [[1.0, 0.0], [2.0, 0.0]])
    with pytest.raises(ValueError, match="readings must be finite"):
        team.correct_robots(1, [0], [[np.nan, 0.0]])
    with pytest.raises(ValueError, match=r"initial_poses must be \(2, 3\)"):
        TeamEKF(2, 3, initial_poses=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="n_robots must be an integer >= 1"):
        TeamEKF(0, 3)
    with pytest.raises(ValueError, match="landmarks must be initialised slots"):
        team.reading_nis(0, [[1.0, 0.0]], landmarks=[0])


# ------------------------------------------------------------------ consistency of robot-to-robot fusion
@pytest.mark.parametrize("variant", ["ekf", "fej"])
def test_robot_to_robot_fusion_is_consistent_monte_carlo(variant):
    """Three robots with odometry and readings of each other only (cooperative localisation), the noise the
    filter models, started at draws from its prior: the joint pose NEES (9 dof), averaged over runs, stays in
    its chi^2 band. Noise small enough for the linearisation to hold (a 3 cm, 0.6 deg reading of robots
    1-2 m away, a 3 cm, 0.6 deg prior)."""
    runs, steps, n = 150, 25, 3
    prior = np.diag([1e-3, 1e-3, 1e-4])
    Q = np.diag([0.03**2, 0.01**2])
    control_cov = CONTROL_COV / 4
    rng = np.random.default_rng(2024)
    nees = np.zeros((runs, steps))
    for run in range(runs):
        truth = np.array([[0.0, 0.0, 0.0], [1.5, 0.5, 1.0], [-0.5, 1.8, -2.0]])
        start = truth + rng.multivariate_normal(np.zeros(3), prior, size=n)
        team = TeamEKF(
            n, 0, FilterSettings(motion_model="odometry", variant=variant), initial_poses=start, initial_pose_covs=prior,
            measurement_noise=Q, resync_every=0,
        )  # fmt: skip
        for t in range(steps):
            for r in range(n):
                nominal = np.array([0.05, 0.1, 0.05])
                truth[r] = odometry_motion(truth[r], *nominal)[0]
                noisy = nominal + rng.multivariate_normal(np.zeros(3), control_cov)
                team.predict(r, noisy, control_cov=control_cov)
            observer = t % n
            targets = np.array([j for j in range(n) if j != observer])
            z = np.array([robot_range_bearing(truth[observer], truth[j], 1e-3)[0] for j in targets])
            z += rng.multivariate_normal(np.zeros(2), Q, size=len(targets))
            team.correct_robots(observer, targets, z)
            error = (team.poses - truth).reshape(-1)
            error[2::3] = [wrap_angle(e) for e in error[2::3]]
            nees[run, t] = error @ np.linalg.solve(team.poses_cov, error)
    dof = 3 * n
    lo, hi = stats.chi2.ppf([0.005, 0.995], dof * runs) / runs
    mean_nees = nees.mean(axis=0)
    # the 99 % band of the mean over runs at each step, with a 15 % margin
    assert np.all(mean_nees > 0.85 * lo), mean_nees
    assert np.all(mean_nees < 1.15 * hi), mean_nees
    assert abs(nees.mean() - dof) < 0.1 * dof
