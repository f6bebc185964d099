"""The region the sensor sees: never past a wall, never out of range or out of the world, and exactly the
sensor's own answer for the landmarks in it."""

from __future__ import annotations

import numpy as np
import pytest

from ekfslam_gym.envs.visibility import visibility_polygon
from ekfslam_gym.sim.sensor import RangeBearingSensor, SensorParams

WALLS = np.array([[0, 0, 10, 0], [10, 0, 10, 8], [10, 8, 0, 8], [0, 8, 0, 0], [4.5, 1.0, 4.5, 5.0]], float)
BOUNDS = np.array([0.0, 0.0, 10.0, 8.0])


def inside(polygon: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Even-odd rule: which points lie inside the closed polygon."""
    x, y = points[:, 0:1], points[:, 1:2]
    a, b = polygon, np.roll(polygon, -1, axis=0)
    crosses = ((a[:, 1] > y) != (b[:, 1] > y)) & (
        x < (b[:, 0] - a[:, 0]) * (y - a[:, 1]) / (b[:, 1] - a[:, 1] + 1e-300) + a[:, 0]
    )
    return crosses.sum(axis=1) % 2 == 1


@pytest.mark.parametrize("fov", [np.pi / 2, np.pi, 2 * np.pi])
def test_the_sensor_reads_the_landmarks_inside_and_none_outside(fov: float) -> None:
    """Landmarks scattered over the room: those the sensor reads from the pose lie inside the polygon, those it
    does not read lie outside (a margin of 2 cm around the polygon's edge is left out: rays are 0.5° apart)."""
    rng = np.random.default_rng(0)
    landmarks = rng.uniform([0.3, 0.3], [9.7, 7.7], size=(4000, 2))
    pose = np.array([3.0, 3.0, 0.3])
    params = SensorParams(min_range=0.0 + 1e-9, max_range=5.0, fov=fov)
    sensor = RangeBearingSensor(landmarks, WALLS, 0.1, params)
    read = np.zeros(len(landmarks), bool)
    read[sensor.true_readings(tuple(pose)).ids] = True
    polygon = visibility_polygon(pose, WALLS, 0.1, 5.0, fov, BOUNDS)
    found = inside(polygon, landmarks)
    edges = np.roll(polygon, -1, axis=0) - polygon
    t = np.clip(
        np.einsum("pkd,kd->pk", landmarks[:, None] - polygon[None], edges)
        / np.einsum("kd,kd->k", edges, edges),
        0,
        1,
    )
    distance = np.linalg.norm(landmarks[:, None] - (polygon[None] + t[..., None] * edges[None]), axis=-1).min(
        1
    )
    clear = distance > 0.02
    assert read.sum() > 100 and (~read).sum() > 100
    np.testing.assert_array_equal(found[clear], read[clear])


def test_the_world_edge_and_the_range_bound_the_polygon() -> None:
    polygon = visibility_polygon(np.array([1.0, 1.0, 0.0]), np.zeros((0, 4)), 0.1, 50.0, 2 * np.pi, BOUNDS)
    assert (polygon >= BOUNDS[:2] - 1e-9).all() and (polygon <= BOUNDS[2:] + 1e-9).all()
    short = visibility_polygon(np.array([5.0, 4.0, 0.0]), np.zeros((0, 4)), 0.1, 2.0, np.pi, BOUNDS)
    assert np.linalg.norm(short - [5.0, 4.0], axis=1).max() <= 2.0 + 1e-9


def test_bad_input_is_named() -> None:
    with pytest.raises(ValueError, match="pose"):
        visibility_polygon(np.array([np.nan, 0, 0]), WALLS, 0.1, 5.0, np.pi)
    with pytest.raises(ValueError, match="fov"):
        visibility_polygon(np.array([1.0, 1.0, 0.0]), WALLS, 0.1, 5.0, 7.0)
