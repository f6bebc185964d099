"""The one angle convention, (-pi, pi]: the scalar, the array and the compiled wrap agree everywhere."""

import math

import numpy as np

from ekfslam_gym.angles import compiled_wrap_angle, wrap_angle, wrap_angles


def test_the_three_wraps_agree_on_random_and_boundary_angles():
    rng = np.random.default_rng(0)
    edges = [
        math.pi,
        -math.pi,
        3 * math.pi,
        -3 * math.pi,
        np.nextafter(math.pi, 4),
        np.nextafter(-math.pi, -4),
        0.0,
    ]
    angles = np.concatenate([rng.uniform(-50, 50, 2000), edges])
    array = wrap_angles(angles)
    scalar = np.array([wrap_angle(a) for a in angles])
    compiled = np.array([compiled_wrap_angle(a) for a in angles])
    np.testing.assert_array_equal(array, scalar)
    np.testing.assert_array_equal(compiled, scalar)
    assert np.all((array > -math.pi) & (array <= math.pi))
    np.testing.assert_allclose(np.sin(array), np.sin(angles), atol=1e-9)
    np.testing.assert_allclose(np.cos(array), np.cos(angles), atol=1e-9)
    assert wrap_angle(math.pi) == math.pi and wrap_angle(-math.pi) == math.pi
