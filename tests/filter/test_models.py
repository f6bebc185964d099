"""Motion and sensor models: Jacobians against central finite differences, limits and conventions."""

import math

import numpy as np
import pytest

from ekfslam_gym.filter.models import (
    inverse_range_bearing,
    odometry_motion,
    range_bearing,
    velocity_motion,
    wheel_motion,
    wrap_angle,
)

EPS = 1e-6


def numeric_jacobian(fn, x, angle_rows=()):
    """Central differences of fn at x; rows listed in angle_rows are differenced modulo 2 pi."""
    x = np.asarray(x, dtype=float)
    f0 = np.asarray(fn(x))
    jac = np.zeros((f0.size, x.size))
    for i in range(x.size):
        step = np.zeros_like(x)
        step[i] = EPS
        diff = np.asarray(fn(x + step)) - np.asarray(fn(x - step))
        for r in angle_rows:
            diff[r] = wrap_angle(diff[r])
        jac[:, i] = diff / (2 * EPS)
    return jac


POSES = [
    np.array([0.3, -1.2, 0.4]),
    np.array([2.0, 1.0, math.pi - 1e-4]),
    np.array([-1.0, 3.0, -math.pi + 1e-4]),
]


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("omega", [0.0, 1e-9, 1e-5, -3e-4, 0.7, -2.0])
def test_velocity_motion_jacobians(pose, omega):
    v, dt = 0.8, 0.1
    _, G, V = velocity_motion(pose, v, omega, dt)
    G_num = numeric_jacobian(lambda p: velocity_motion(p, v, omega, dt)[0], pose, angle_rows=(2,))
    V_num = numeric_jacobian(lambda c: velocity_motion(pose, c[0], c[1], dt)[0], [v, omega], angle_rows=(2,))
    np.testing.assert_allclose(G, G_num, atol=1e-7)
    np.testing.assert_allclose(V, V_num, atol=1e-7)


def test_velocity_motion_matches_corrected_textbook_form():
    pose = np.array([1.0, 2.0, 0.3])
    v, omega, dt = 1.5, 0.9, 0.2
    new_pose, _, _ = velocity_motion(pose, v, omega, dt)
    ratio = v / omega
    expected = [
        pose[0] - ratio * math.sin(pose[2]) + ratio * math.sin(pose[2] + omega * dt),
        pose[1]
        + ratio * math.cos(pose[2])
        - ratio * math.cos(pose[2] + omega * dt),  # the course's lecture notes had -, +
        pose[2] + omega * dt,
    ]
    np.testing.assert_allclose(new_pose, expected, rtol=0, atol=1e-12)


def test_velocity_motion_is_continuous_through_zero_turn_rate():
    pose = np.array([0.0, 0.0, 0.5])
    straight, G0, V0 = velocity_motion(pose, 1.0, 0.0, 0.1)
    np.testing.assert_allclose(straight[:2], 0.1 * np.array([math.cos(0.5), math.sin(0.5)]), atol=1e-15)
    for omega in (1e-12, 1e-6, 1e-4 * 0.999, 1e-4 * 1.001):
        near, G, V = velocity_motion(pose, 1.0, omega, 0.1)
        np.testing.assert_allclose(near, straight, atol=2e-5 * omega / 1e-4 + 1e-12)
        np.testing.assert_allclose(V, V0, atol=1e-5)


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("control", [(0.1, 0.5, -0.2), (0.0, 0.0, 0.3), (math.pi - 1e-3, 0.2, 0.1)])
def test_odometry_motion_jacobians(pose, control):
    _, G, V = odometry_motion(pose, *control)
    G_num = numeric_jacobian(lambda p: odometry_motion(p, *control)[0], pose, angle_rows=(2,))
    V_num = numeric_jacobian(lambda c: odometry_motion(pose, c[0], c[1], c[2])[0], control, angle_rows=(2,))
    np.testing.assert_allclose(G, G_num, atol=1e-7)
    np.testing.assert_allclose(V, V_num, atol=1e-7)


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("landmark", [(3.0, 4.0), (-2.5, 0.1), (0.5, -3.0)])
def test_range_bearing_jacobians(pose, landmark):
    landmark = np.array(landmark)
    _, Hx, Hm = range_bearing(pose, landmark, 1e-3)
    Hx_num = numeric_jacobian(lambda p: range_bearing(p, landmark, 1e-3)[0], pose, angle_rows=(1,))
    Hm_num = numeric_jacobian(lambda m: range_bearing(pose, m, 1e-3)[0], landmark, angle_rows=(1,))
    np.testing.assert_allclose(Hx, Hx_num, atol=1e-7)
    np.testing.assert_allclose(Hm, Hm_num, atol=1e-7)


def test_range_bearing_behind_the_robot_wraps_and_guards_tiny_ranges():
    z, _, _ = range_bearing(np.array([0.0, 0.0, 0.0]), np.array([-1.0, 1e-12]), 1e-3)
    assert z[1] == pytest.approx(math.pi)
    z, _, _ = range_bearing(np.array([0.0, 0.0, 0.0]), np.array([-1.0, -1e-12]), 1e-3)
    assert z[1] == pytest.approx(-math.pi)
    z, Hx, Hm = range_bearing(np.array([0.0, 0.0, 0.0]), np.array([1e-9, 0.0]), 1e-3)
    assert np.all(np.isfinite(Hx)) and np.all(np.isfinite(Hm))
    assert abs(Hm[1, 1]) <= 1 / 1e-3**2 * 1e-9 + 1e-12


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("reading", [(2.0, 0.3), (0.5, math.pi - 1e-4), (4.0, -2.0)])
def test_inverse_range_bearing_jacobians_and_round_trip(pose, reading):
    reading = np.array(reading)
    landmark, Gr, Gz = inverse_range_bearing(pose, reading)
    Gr_num = numeric_jacobian(lambda p: inverse_range_bearing(p, reading)[0], pose)
    Gz_num = numeric_jacobian(lambda z: inverse_range_bearing(pose, z)[0], reading)
    np.testing.assert_allclose(Gr, Gr_num, atol=1e-7)
    np.testing.assert_allclose(Gz, Gz_num, atol=1e-7)
    assert np.linalg.det(Gz) == pytest.approx(reading[0])
    z, _, _ = range_bearing(pose, landmark, 1e-3)
    assert z[0] == pytest.approx(reading[0])
    assert wrap_angle(z[1] - reading[1]) == pytest.approx(0.0, abs=1e-12)


def test_wrap_angle_range():
    assert wrap_angle(math.pi) == math.pi
    assert wrap_angle(-math.pi) == math.pi
    assert wrap_angle(3 * math.pi) == pytest.approx(math.pi)
    for a in np.linspace(-20, 20, 1001):
        w = wrap_angle(a)
        assert -math.pi < w <= math.pi
        assert math.isclose(math.sin(w), math.sin(a), abs_tol=1e-12)
        assert math.isclose(math.cos(w), math.cos(a), abs_tol=1e-12)


WHEEL_BASE = 0.3


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize(
    "control",
    [
        (0.05, 0.05, 0.0),  # straight ahead
        (-0.04, -0.04, 0.002),  # backward, with a little slip
        (-0.015, 0.015, 0.0),  # turning in place
        (0.03, 0.07, -0.01),  # an arc and a slide
        (0.02, 0.02 + 1e-5, 0.0),  # a turn of 3e-5 rad: the sinc series
        (0.01, 0.01, 0.04),  # sliding sideways along a wall
    ],
)
def test_wheel_motion_jacobians(pose, control):
    _, G, V = wheel_motion(pose, *control, WHEEL_BASE)
    G_num = numeric_jacobian(lambda p: wheel_motion(p, *control, WHEEL_BASE)[0], pose, angle_rows=(2,))
    V_num = numeric_jacobian(
        lambda c: wheel_motion(pose, c[0], c[1], c[2], WHEEL_BASE)[0], control, angle_rows=(2,)
    )
    np.testing.assert_allclose(G, G_num, atol=1e-7)
    np.testing.assert_allclose(V, V_num, atol=1e-7)


def test_wheel_motion_is_the_arc_of_the_velocity_model_plus_the_slip():
    """Without slip the wheels model is the velocity model with v dt = (l + r)/2, omega dt = (r - l)/b; the
    slip moves the pose sideways, perpendicular to the mid-heading, and leaves the heading alone."""
    rng = np.random.default_rng(3)
    for _ in range(200):
        pose = rng.uniform(-3, 3, 3)
        left, right = rng.uniform(-0.1, 0.1, 2)
        moved, _, _ = wheel_motion(pose, left, right, 0.0, WHEEL_BASE)
        arc, _, _ = velocity_motion(pose, 0.5 * (left + right) / 0.1, (right - left) / WHEEL_BASE / 0.1, 0.1)
        np.testing.assert_allclose(moved, arc, atol=1e-12)
        slid, _, _ = wheel_motion(pose, left, right, 0.03, WHEEL_BASE)
        mid = pose[2] + 0.5 * (right - left) / WHEEL_BASE
        np.testing.assert_allclose(
            slid[:2] - moved[:2], 0.03 * np.array([-math.sin(mid), math.cos(mid)]), atol=1e-12
        )
        assert slid[2] == moved[2]
