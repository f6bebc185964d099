"""Odometry: the decomposition is exact, the noise has exactly the reported covariance, and a filter that
predicts with the measured (rot1, trans, rot2) and V M V^T is consistent on the simulated robot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ekfslam_gym.filter.models import wheel_motion
from ekfslam_gym.sim import (
    OdometryNoise,
    VelocityNoise,
    WheelOdometryNoise,
    World,
    compose_odometry,
    decompose_odometry,
    decompose_wheels,
    make_layout,
    velocity_from_motion,
)
from ekfslam_gym.sim.odometry import measure_odometry, measure_velocity, measure_wheels


def _random_poses(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    pose0 = rng.uniform((-10, -10, -10), (10, 10, 10), size=(n, 3))
    step = rng.normal(0.0, 0.2, size=(n, 3)) * rng.choice([0.0, 1e-3, 1.0, 20.0], size=(n, 1))
    return pose0, pose0 + step


def test_decomposition_reproduces_the_displacement_exactly() -> None:
    pose0, pose1 = _random_poses(np.random.default_rng(0), 5000)
    for p0, p1 in zip(pose0, pose1):
        u = np.array(decompose_odometry(*p0, *p1))
        assert np.all(np.isfinite(u)) and abs(u[0]) <= math.pi / 2
        assert np.allclose(compose_odometry(p0, u), p1, rtol=0.0, atol=1e-9)


def test_decomposition_of_special_motions() -> None:
    # pure rotation: rot1 finite (0), no translation, the whole turn in rot2
    assert decompose_odometry(1.0, 2.0, 0.3, 1.0, 2.0, 0.8) == (0.0, 0.0, pytest.approx(0.5))
    # reversing is a negative translation, not two half-turns
    rot1, trans, rot2 = decompose_odometry(0.0, 0.0, 0.0, -0.1, 0.0, 0.0)
    assert (rot1, trans, rot2) == (pytest.approx(0.0), pytest.approx(-0.1), pytest.approx(0.0))
    # a heading change of more than pi within a step is kept, not aliased by wrapping
    assert decompose_odometry(0.0, 0.0, 3.0, 0.0, 0.0, 3.0 + 4.0)[2] == pytest.approx(4.0)


@pytest.mark.parametrize(
    "pose1", [(0.1, 0.0, 0.0), (0.08, 0.03, 0.2), (0.0, 0.0, 0.15), (-0.05, 0.01, -0.1), (1e-4, 2e-4, 0.0)]
)
def test_odometry_noise_has_the_reported_covariance(pose1: tuple[float, float, float]) -> None:
    rng = np.random.default_rng(1)
    pose0 = (0.0, 0.0, 0.0)
    noise = OdometryNoise()
    readings = [measure_odometry(pose0, pose1, noise, rng) for _ in range(20000)]
    u_true = readings[0].u_true
    cov = readings[0].cov
    assert all(np.array_equal(r.u_true, u_true) and np.array_equal(r.cov, cov) for r in readings)
    assert np.allclose(compose_odometry(np.array(pose0), u_true), pose1, atol=1e-12)
    errors = np.array([r.u for r in readings]) - u_true
    empirical = np.cov(errors.T)
    # variances within 5 % (the standard error of a variance from 20000 samples is 1 %), no correlations
    assert np.allclose(np.diag(empirical), np.diag(cov), rtol=0.05)
    corr = empirical / np.sqrt(np.outer(np.diag(empirical), np.diag(empirical)))
    assert np.all(np.abs(corr[~np.eye(3, dtype=bool)]) < 0.05)
    assert np.all(np.abs(errors.mean(axis=0)) < 4.0 * np.sqrt(np.diag(cov) / len(errors)))


def test_velocity_noise_has_the_reported_covariance() -> None:
    rng = np.random.default_rng(2)
    readings = [measure_velocity((0.0, 0.0, 0.0), (0.05, 0.002, 0.08), 0.1, VelocityNoise(), rng)
                for _ in range(20000)]  # fmt: skip
    errors = np.array([r.u for r in readings]) - readings[0].u_true
    assert np.allclose(np.diag(np.cov(errors.T)), np.diag(readings[0].cov), rtol=0.05)


def test_velocity_form_inverts_the_chord_model() -> None:
    rng = np.random.default_rng(3)
    for _ in range(1000):
        x, y, theta = rng.uniform(-5, 5, 3)
        v, omega, dt = rng.uniform(-1, 1), rng.uniform(-2, 2), 0.1
        a = omega * dt
        sinc = math.sin(a / 2) / (a / 2) if a else 1.0
        x1 = x + v * dt * sinc * math.cos(theta + a / 2)
        y1 = y + v * dt * sinc * math.sin(theta + a / 2)
        assert velocity_from_motion(x, y, theta, x1, y1, theta + a, dt) == pytest.approx((v, omega), abs=1e-9)


def _odometry_jacobians(pose: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """G = d pose'/d pose and V = d pose'/d u of the odometry model at (pose, u)."""
    heading = pose[2] + u[0]
    c, s = math.cos(heading), math.sin(heading)
    G = np.array([[1.0, 0.0, -u[1] * s], [0.0, 1.0, u[1] * c], [0.0, 0.0, 1.0]])
    V = np.array([[-u[1] * s, c, 0.0], [u[1] * c, s, 0.0], [1.0, 0.0, 1.0]])
    return G, V


def _dead_reckoning_nees(rng: np.random.Generator, n_segments: int, steps: int) -> np.ndarray:
    """NEES of dead reckoning over ``steps`` steps from the true pose with the measured (rot1, trans, rot2)
    and the reported M, the way a filter's prediction uses them (P <- G P G^T + V M V^T, P_0 = 0).

    Several steps, not one: after a single step V M V^T is singular across the direction of travel (a
    pure rotation moves nothing sideways to first order), so a one-step NEES is dominated by that
    linearisation, not by the simulator."""
    world = World(make_layout("arena", rng, 0))
    nees = []
    command = None
    while len(nees) < n_segments:
        estimate = world.last_motion[1]
        P = np.zeros((3, 3))
        collided = False
        for _ in range(steps):
            if command is None or rng.random() < 0.3:
                command = rng.uniform((-1.0, -2.0), (1.0, 2.0))
            if world.step(*command):
                collided = True
                break
            reading = world.odometry(rng)
            G, V = _odometry_jacobians(estimate, reading.u)
            estimate = compose_odometry(estimate, reading.u)
            P = G @ P @ G.T + V @ reading.cov @ V.T
        if collided:
            world = World(make_layout("arena", rng, 0))
            continue
        error = estimate - world.last_motion[1]
        nees.append(error @ np.linalg.solve(P, error))
    return np.array(nees)


def test_dead_reckoning_with_measured_odometry_is_consistent() -> None:
    """A prototype that read odometry off the body's chord and heading change was over-confident by 2-3x;
    here the mean NEES of dead reckoning on the simulated robot must be 3 (chi-square, 3 dof)."""
    nees = _dead_reckoning_nees(np.random.default_rng(4), 800, 8)
    assert abs(nees.mean() - 3.0) < 0.35  # the mean of 800 chi2(3) samples has std 0.09
    assert np.mean(nees < 7.815) == pytest.approx(0.95, abs=0.025)  # the 95 % quantile of chi2(3)


def test_first_odometry_is_zero_motion_with_floor_noise() -> None:
    world = World(make_layout("arena", np.random.default_rng(5), 0))
    reading = world.odometry(np.random.default_rng(6))
    assert np.array_equal(reading.u_true, np.zeros(3))
    assert np.allclose(np.diag(reading.cov), [1e-6, 1e-6, 1e-6])


def test_noise_parameters_are_validated() -> None:
    with pytest.raises(ValueError, match="alpha1"):
        OdometryNoise(alpha1=-0.1)
    with pytest.raises(ValueError, match="floors"):
        OdometryNoise(rot_floor=0.0)
    with pytest.raises(ValueError, match="alpha3"):
        VelocityNoise(alpha3=float("nan"))


def test_world_odometry_decomposes_the_true_motion_exactly() -> None:
    rng = np.random.default_rng(7)
    world = World(make_layout("rooms", rng, 0))
    for k in range(500):
        if k % 10 == 0:
            command = rng.uniform((-1.0, -2.0), (1.0, 2.0))
        if world.step(*command):
            world = World(make_layout("rooms", rng, 0))
            continue
        pose0, pose1 = world.last_motion
        reading = world.odometry(rng)
        assert np.allclose(compose_odometry(pose0, reading.u_true), pose1, rtol=0.0, atol=1e-12)


def test_velocity_form_recovers_a_steady_command_in_free_space() -> None:
    world = World(make_layout("arena", np.random.default_rng(8), 0, width=200.0, height=200.0))
    rng = np.random.default_rng(9)
    for _ in range(3):  # past the one-substep lag
        world.step(0.7, -1.3)
    reading = world.velocity_odometry(rng)
    assert reading.u_true == pytest.approx([0.7, -1.3], rel=1e-3)
    assert reading.cov.shape == (2, 2) and np.all(np.diag(reading.cov) > 0)


# --- wheel odometry -------------------------------------------------------------------------------------------


def test_wheel_decomposition_is_the_exact_inverse_of_the_wheels_model() -> None:
    rng = np.random.default_rng(10)
    base = WheelOdometryNoise().wheel_base
    pose0 = rng.uniform((-10, -10, -10), (10, 10, 10), size=(3000, 3))
    step = rng.normal(0.0, 0.1, size=(3000, 3)) * rng.choice([0.0, 1e-3, 1.0, 10.0], size=(3000, 1))
    for p0, p1 in zip(pose0, pose0 + step):
        left, right, slip = decompose_wheels(*p0, *p1, base)
        moved, _, _ = wheel_motion(p0, left, right, slip, base)
        assert np.allclose(moved[:2], p1[:2], rtol=0.0, atol=1e-9)
        assert abs((moved[2] - p1[2] + math.pi) % (2 * math.pi) - math.pi) < 1e-12
        assert (right - left) / base == pytest.approx(p1[2] - p0[2], abs=1e-12)


def _jittery_world(seed: int, size: float = 200.0) -> World:
    return World(make_layout("arena", np.random.default_rng(seed), 0, width=size, height=size))


@pytest.mark.parametrize("sensed", [True, False])
def test_wheel_noise_has_the_reported_covariance_in_free_space(sensed: bool) -> None:
    """Whatever the commands (a new one every step, backward, turning in place), free-space wheel odometry
    errs by exactly N(0, M): the wheels by their drawn noise, the slip (sensed or integrated from the
    substeps' arcs) by its floor or not at all."""
    rng = np.random.default_rng(11)
    noise = WheelOdometryNoise(slide_sensed=sensed)
    world = World(make_layout("arena", rng, 0, width=200.0, height=200.0), wheel_noise=noise)
    normalised = []
    for _ in range(20000):
        assert not world.step(*rng.uniform((-1.0, -2.0), (1.0, 2.0)))
        reading = world.wheel_odometry(rng)
        error = reading.u - reading.u_true
        std = np.sqrt(np.diag(reading.cov))
        assert np.count_nonzero(reading.cov - np.diag(np.diag(reading.cov))) == 0
        if not sensed:
            # the slip of two arcs in one step (a command change) is integrated exactly
            assert abs(error[2]) < 1e-12
            error[2] = 0.0
        normalised.append(error / std)
    normalised = np.array(normalised)
    empirical = np.cov(normalised.T)
    wheels = slice(0, 3 if sensed else 2)
    # unit variances within 5 % (the standard error of a variance from 20000 samples is 1 %), no correlations
    np.testing.assert_allclose(np.diag(empirical)[wheels], 1.0, rtol=0.05)
    assert np.all(np.abs(empirical[wheels, wheels][~np.eye(3 if sensed else 2, dtype=bool)]) < 0.05)
    assert np.all(np.abs(normalised.mean(axis=0)) < 4.0 / math.sqrt(len(normalised)))


def test_wheel_noise_grows_with_each_wheels_travel() -> None:
    noise = WheelOdometryNoise()
    trace = [(0.0, 0.0, 0.0), (0.0, 0.0, 0.05), (0.0, 0.0, 0.1)]  # turning in place
    reading = measure_wheels(trace, noise, 0.0, np.random.default_rng(12))
    travel = 0.5 * noise.wheel_base * 0.1
    assert reading.u_true == pytest.approx([-travel, travel, 0.0], abs=1e-15)
    expected = (noise.wheel_alpha * travel + noise.wheel_floor) ** 2
    np.testing.assert_allclose(np.diag(reading.cov), [expected, expected, noise.slip_floor**2], rtol=1e-12)
    contact = measure_wheels(trace, noise, 0.1, np.random.default_rng(12))
    assert contact.cov[2, 2] == pytest.approx((noise.slip_floor + noise.slip_contact * 0.1) ** 2)


def _contact_slides(noise: WheelOdometryNoise) -> dict[str, np.ndarray]:
    """Per step in contact while circling blindly (6.5 m at 0.55 m/s, the circle baseline's radius) into the
    walls of a few arenas: the slip error and its reported std, the true turn, and the turn-drive-turn rot1."""
    out: dict[str, list[float]] = {"error": [], "std": [], "turn": [], "rot1": []}
    for seed in range(8):
        rng = np.random.default_rng([13, seed])
        world = World(make_layout("arena", rng, 0), wheel_noise=noise)
        for _ in range(300):
            contact = world.step(0.55, 0.55 / 6.5)
            reading = world.wheel_odometry(rng)
            if contact:
                out["error"].append(reading.u[2] - reading.u_true[2])
                out["std"].append(math.sqrt(reading.cov[2, 2]))
                out["turn"].append((reading.u_true[1] - reading.u_true[0]) / noise.wheel_base)
                out["rot1"].append(world.odometry(rng).u_true[0])
    return {key: np.array(value) for key, value in out.items()}


def test_wall_contact_is_a_sideways_slip_not_a_turn() -> None:
    """Sliding along a wall: the turn is still exactly the commanded one (the wheels' difference) and the slide
    is a slip, where the turn-drive-turn model reads turns of tens of degrees. Unsensed, the slip's reported
    variance is calibrated to the slides (the rms of the normalised slide about 1: measured 1.00 at these
    seeds); sensed, the slip errs by exactly the reported noise."""
    unsensed = _contact_slides(WheelOdometryNoise(slide_sensed=False))
    errors = unsensed["error"]
    assert len(errors) > 300
    np.testing.assert_allclose(unsensed["turn"], 0.1 * 0.55 / 6.5, rtol=0, atol=1e-9)
    assert np.median(np.abs(unsensed["rot1"])) > 0.3  # rad
    assert np.sqrt(np.mean(errors**2)) > 0.005  # m: the slides are real and the wheels miss them
    assert 0.6 < np.sqrt(np.mean((errors / unsensed["std"]) ** 2)) < 1.4
    sensed = _contact_slides(WheelOdometryNoise())
    normalised = sensed["error"] / sensed["std"]
    assert np.mean(normalised) == pytest.approx(0.0, abs=4.0 / math.sqrt(len(normalised)))
    assert np.var(normalised) == pytest.approx(1.0, rel=0.15)


def _dead_reckoning_nees_wheels(rng: np.random.Generator, n_segments: int, steps: int) -> np.ndarray:
    """As ``_dead_reckoning_nees`` with the wheels model, driving on through wall contact (the slide sensed)."""
    world = World(make_layout("arena", rng, 0))
    base = world.wheel_noise.wheel_base
    nees = []
    for _ in range(n_segments):
        estimate = world.last_motion[1]
        P = np.zeros((3, 3))
        for _ in range(steps):
            world.step(*rng.uniform((-1.0, -2.0), (1.0, 2.0)))
            reading = world.wheel_odometry(rng)
            estimate, G, V = wheel_motion(estimate, *reading.u, base)
            P = G @ P @ G.T + V @ reading.cov @ V.T
        error = world.last_motion[1] - estimate
        error[2] = (error[2] + math.pi) % (2 * math.pi) - math.pi
        nees.append(error @ np.linalg.solve(P, error))
    return np.array(nees)


def test_dead_reckoning_with_wheel_odometry_is_consistent() -> None:
    """Jittery commands (a new one every step, the worst case of the turn-drive-turn model's arc residual)."""
    nees = _dead_reckoning_nees_wheels(np.random.default_rng(14), 800, 8)
    assert abs(nees.mean() - 3.0) < 0.35  # the mean of 800 chi2(3) samples has std 0.09
    assert np.mean(nees < 7.815) == pytest.approx(0.95, abs=0.025)


def test_wheel_noise_parameters_are_validated() -> None:
    with pytest.raises(ValueError, match="wheel_alpha"):
        WheelOdometryNoise(wheel_alpha=-0.1)
    with pytest.raises(ValueError, match="floors"):
        WheelOdometryNoise(slip_floor=0.0)
    with pytest.raises(ValueError, match="wheel_base"):
        WheelOdometryNoise(wheel_base=float("nan"))
    with pytest.raises(ValueError, match="slide_sensed"):
        WheelOdometryNoise(slide_sensed=1)


def test_world_pickles_its_wheel_odometry() -> None:
    import pickle

    noise = WheelOdometryNoise(wheel_alpha=0.03, slide_sensed=False)
    world = World(make_layout("arena", np.random.default_rng(15), 3), wheel_noise=noise)
    world.step(0.5, 0.3)
    clone = pickle.loads(pickle.dumps(world))
    assert clone.wheel_noise == noise
    a = world.wheel_odometry(np.random.default_rng(1))
    b = clone.wheel_odometry(np.random.default_rng(1))
    assert np.array_equal(a.u, b.u) and np.array_equal(a.cov, b.cov)


def test_substep_poses_agree_between_chipmunk_calls_and_pymunks_python_api() -> None:
    """Unsensed slides integrate the substep poses: the direct Chipmunk path records the same poses as pymunk's
    Python API, bit for bit (the readings built from them agree exactly), through wall contacts."""
    noise = WheelOdometryNoise(slide_sensed=False)
    fast, slow = (
        World(make_layout("rooms", np.random.default_rng(4), 30), wheel_noise=noise) for _ in range(2)
    )
    assert fast.robot._chipmunk is not None
    slow.robot._chipmunk = None
    rng = np.random.default_rng(4)
    contacts = 0
    for k in range(400):
        if k % 10 == 0:
            command = rng.uniform((-1.0, -2.0), (1.0, 2.0))
        contacts += fast.step(*command)
        slow.step(*command)
        a = fast.wheel_odometry(np.random.default_rng(k))
        b = slow.wheel_odometry(np.random.default_rng(k))
        assert np.array_equal(a.u, b.u) and np.array_equal(a.cov, b.cov), k
        assert fast.pose_tuple == slow.pose_tuple, k
    assert contacts > 0
