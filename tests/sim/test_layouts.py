"""Layout generators: exact landmark counts, spacing, clearance, reachability, start pose, determinism."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from ekfslam_gym.sim import LAYOUTS, Layout, make_layout, place_landmarks
from ekfslam_gym.sim.geometry import min_wall_distance

# the generators that draw their landmarks; ``surveyed`` is given them (tested at the end), ``map_server`` reads
# a map file (tests/sim/test_map_server.py)
NAMES = sorted(set(LAYOUTS) - {"surveyed", "map_server"})


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("n_landmarks", [0, 1, 30, 120])
def test_layout_invariants(name: str, n_landmarks: int) -> None:
    for seed in range(3):
        layout = make_layout(name, np.random.default_rng(seed), n_landmarks, min_spacing=1.0)
        assert layout.name == name
        assert layout.landmarks.shape == (n_landmarks, 2) and layout.landmarks.dtype == np.float64
        assert layout.walls.ndim == 2 and layout.walls.shape[1] == 4 and len(layout.walls) >= 4
        assert layout.start.shape == (3,) and layout.bounds.shape == (4,)
        xmin, ymin, xmax, ymax = layout.bounds
        lm = layout.landmarks
        assert np.all((lm[:, 0] > xmin) & (lm[:, 0] < xmax) & (lm[:, 1] > ymin) & (lm[:, 1] < ymax))
        if n_landmarks:
            assert min_wall_distance(lm, layout.walls).min() >= 0.5  # default landmark_clearance
        if n_landmarks > 1:
            gaps = np.hypot(*(lm[:, None, :] - lm[None, :, :]).transpose(2, 0, 1))
            assert gaps[~np.eye(n_landmarks, dtype=bool)].min() >= 1.0
        assert min_wall_distance(layout.start[None, :2], layout.walls)[0] >= 1.0  # default start_clearance
        assert -np.pi <= layout.start[2] <= np.pi


@pytest.mark.parametrize("name", NAMES)
def test_layout_is_deterministic_in_the_generator_state(name: str) -> None:
    a = make_layout(name, np.random.default_rng(7), 30)
    b = make_layout(name, np.random.default_rng(7), 30)
    c = make_layout(name, np.random.default_rng(8), 30)
    for field in ("walls", "landmarks", "start", "bounds"):
        assert np.array_equal(getattr(a, field), getattr(b, field))
    assert not np.array_equal(a.landmarks, c.landmarks)


def test_layout_arrays_are_read_only_also_after_pickling() -> None:
    layout = make_layout("arena", np.random.default_rng(0), 5)
    twin = pickle.loads(pickle.dumps(layout))
    assert np.array_equal(twin.landmarks, layout.landmarks) and twin.name == layout.name
    for item in (layout, twin):
        with pytest.raises(ValueError):
            item.landmarks[0, 0] = 1.0


def test_loop_landmarks_are_in_the_ring_not_in_the_block() -> None:
    for seed in range(5):
        layout = make_layout("loop", np.random.default_rng(seed), 60)
        block = layout.walls[4:]  # the central block's four walls follow the boundary's four
        x0, x1 = block[:, [0, 2]].min(), block[:, [0, 2]].max()
        y0, y1 = block[:, [1, 3]].min(), block[:, [1, 3]].max()
        lm = layout.landmarks
        inside = (lm[:, 0] > x0) & (lm[:, 0] < x1) & (lm[:, 1] > y0) & (lm[:, 1] < y1)
        assert not inside.any()
        sx, sy = layout.start[:2]
        assert not (x0 < sx < x1 and y0 < sy < y1)


def test_landmarks_are_never_placed_in_an_unreachable_enclosure() -> None:
    # a closed 8 x 8 m box in a 20 x 20 m arena: plenty of room inside, but the robot starts outside it
    walls = np.array([[0, 0, 20, 0], [20, 0, 20, 20], [20, 20, 0, 20], [0, 20, 0, 0],
                      [6, 6, 14, 6], [14, 6, 14, 14], [14, 14, 6, 14], [6, 14, 6, 6]], dtype=float)  # fmt: skip
    bounds = np.array([0.0, 0.0, 20.0, 20.0])
    start = np.array([2.0, 2.0, 0.0])
    lm = place_landmarks(
        np.random.default_rng(0), 150, walls, bounds, start,
        min_spacing=0.8, landmark_clearance=0.5, robot_radius=0.2, wall_radius=0.05,
    )  # fmt: skip
    inside = (lm[:, 0] > 6) & (lm[:, 0] < 14) & (lm[:, 1] > 6) & (lm[:, 1] < 14)
    assert len(lm) == 150 and not inside.any()
    # started inside, every landmark is inside
    lm_in = place_landmarks(
        np.random.default_rng(0), 10, walls, bounds, np.array([10.0, 10.0, 0.0]),
        min_spacing=0.8, landmark_clearance=0.5, robot_radius=0.2, wall_radius=0.05,
    )  # fmt: skip
    assert np.all((lm_in > 6) & (lm_in < 14))


def test_rooms_spread_landmarks_over_every_room() -> None:
    layout = make_layout("rooms", np.random.default_rng(3), 90, jitter=0.0)
    col = np.minimum((layout.landmarks[:, 0] // (20 / 3)).astype(int), 2)
    row = np.minimum((layout.landmarks[:, 1] // (20 / 3)).astype(int), 2)
    assert len(set(zip(col.tolist(), row.tolist()))) == 9


@pytest.mark.parametrize("name", NAMES)
def test_impossible_landmark_count_raises(name: str) -> None:
    with pytest.raises(ValueError, match="could place only"):
        make_layout(name, np.random.default_rng(0), 2000, min_spacing=1.0)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"n_landmarks": -1},
        {"n_landmarks": 2.5},
        {"landmark_clearance": 0.2},  # not more than robot radius + wall radius
        {"min_spacing": -1.0},
        {"width": 1.0},
    ],
)
def test_bad_layout_arguments_raise(kwargs: dict) -> None:
    n = kwargs.pop("n_landmarks", 10)
    with pytest.raises(ValueError):
        make_layout("arena", np.random.default_rng(0), n, **kwargs)


def test_unknown_layout_and_bad_rng() -> None:
    with pytest.raises(ValueError, match="unknown layout"):
        make_layout("castle", np.random.default_rng(0), 5)
    with pytest.raises(TypeError):
        make_layout("arena", 0, 5)  # type: ignore[arg-type]


def test_layout_validates_shapes() -> None:
    with pytest.raises(ValueError, match="walls"):
        Layout("x", np.zeros((2, 3)), np.zeros((0, 2)), np.zeros(3), np.zeros(4), 0.05)
    with pytest.raises(ValueError, match="start"):
        Layout("x", np.zeros((0, 4)), np.zeros((0, 2)), np.zeros(2), np.zeros(4), 0.05)
    with pytest.raises(ValueError, match="finite"):
        Layout("x", np.zeros((0, 4)), np.full((1, 2), np.nan), np.zeros(3), np.zeros(4), 0.05)


@pytest.mark.parametrize("name", NAMES)
def test_the_free_space_cache_changes_no_layout(name):
    from ekfslam_gym.sim import layouts

    def generate(seed, clear):
        if clear:
            layouts._grid_cache.clear()
        return make_layout(name, np.random.default_rng(seed), 12)

    warm = [generate(seed, clear=False) for seed in range(6)]
    cold = [generate(seed, clear=True) for seed in range(6)]
    for a, b in zip(warm, cold):
        np.testing.assert_array_equal(a.landmarks, b.landmarks)
        np.testing.assert_array_equal(a.walls, b.walls)
        np.testing.assert_array_equal(a.start, b.start)
    assert 0 < len(layouts._grid_cache) <= layouts._GRID_CACHE_SIZE


def test_surveyed_layout_keeps_the_landmarks_it_is_given() -> None:
    rng = np.random.default_rng(0)
    layout = make_layout("surveyed", rng, 2, landmarks=[[1.0, 1.0], [3.0, 2.0]], width=4.0, height=3.0)
    np.testing.assert_array_equal(layout.landmarks, [[1.0, 1.0], [3.0, 2.0]])
    assert min_wall_distance(layout.start[None, :2], layout.walls)[0] >= 1.0
    with pytest.raises(ValueError, match="n_landmarks is 3 but 2 landmarks"):
        make_layout("surveyed", rng, 3, landmarks=[[1.0, 1.0], [3.0, 2.0]], width=4.0, height=3.0)
    with pytest.raises(ValueError, match="inside the 4.0 x 3.0 m rectangle"):
        make_layout("surveyed", rng, 1, landmarks=[[5.0, 1.0]], width=4.0, height=3.0)
