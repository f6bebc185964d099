"""The belief image (observation.belief_image): known answers of the compiled kernels, the env's image against an
independent numpy reading of its memories, belief-only inputs, determinism, validation."""

import copy
import math

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401  (registers the envs)
from ekfslam_gym import compiled
from ekfslam_gym.envs import EKFSLAMEnv, EnvConfig

BELIEF = {"kind": "dict", "belief_image": True}


def image_of(size, coverage, walls, bounds, mean, cov, observed, resolution, extent):
    """The kernel's image as a (3, size, size) array."""
    out = np.full(3 * size * size, np.nan, dtype=np.float32)
    compiled.fill_belief_image(out, size, coverage, walls, bounds, mean, cov, observed, resolution, extent)
    return out.reshape(3, size, size)


def belief(pose, landmarks, variances, observed):
    """Filter mean, covariance (diagonal) and observed flags for a pose and landmark estimates."""
    n = len(landmarks)
    mean = np.concatenate([np.asarray(pose, float), np.asarray(landmarks, float).reshape(-1)])
    cov = np.diag(np.concatenate([[1e-4, 1e-4, 1e-6], np.repeat(np.asarray(variances, float), 2)]))
    return mean, np.ascontiguousarray(cov), np.asarray(observed, dtype=bool).reshape(n)


def to_world(pose, forward, left):
    x, y, theta = pose
    return x + math.cos(theta) * forward - math.sin(theta) * left, y + math.sin(theta) * forward + math.cos(
        theta
    ) * left


BOUNDS = np.array([0.0, 0.0, 10.0, 10.0])


def empty_memory():
    return np.zeros((20, 20))


def test_a_landmark_ahead_lands_in_its_cell_weighted_by_its_certainty():
    pose = (4.3, 5.1, 0.3)
    # 16 cells over 8 m each side: 1 m cells; (forward 2.5, left 1.2) is row floor(8 - 1.2) = 6, column
    # floor(2.5 + 8) = 10. A second estimate shares the cell (the larger certainty wins), one is unseen and one
    # lies beyond the window.
    ahead = to_world(pose, 2.5, 1.2)
    shared = to_world(pose, 2.9, 1.9)
    unseen = to_world(pose, -3.5, -3.5)
    far = to_world(pose, 8.5, 0.0)
    mean, cov, observed = belief(
        pose, [ahead, shared, unseen, far], [0.045, 0.5, 0.01, 0.01], [True, True, False, True]
    )
    image = image_of(16, empty_memory(), empty_memory(), BOUNDS, mean, cov, observed, 0.5, 8.0)
    expected = np.zeros((16, 16), dtype=np.float32)
    expected[6, 10] = 1.0 / (1.0 + math.sqrt(2 * 0.045) / 1.0)  # sqrt(tr Sigma_jj) = 0.3 m, cell 1 m
    np.testing.assert_allclose(image[1], expected, rtol=1e-6)
    assert image[1, 6, 10] == pytest.approx(1 / 1.3, rel=1e-6)


def test_the_coverage_channel_is_the_memory_where_the_window_lies_on_it():
    # Cells as large as the memory's (8 cells over 2 m each side, 0.5 m) and the robot on a memory-cell corner,
    # facing +x: image cell (row, col) is memory cell (13 - row, 6 + col), row 0 furthest to the left (+y).
    rng = np.random.default_rng(0)
    coverage = (rng.random((20, 20)) < 0.5).astype(float)
    mean, cov, observed = belief((5.0, 5.0, 0.0), [(1.0, 1.0)], [1.0], [False])
    image = image_of(8, coverage, empty_memory(), BOUNDS, mean, cov, observed, 0.5, 2.0)
    np.testing.assert_array_equal(image[0], coverage[6:14, 6:14][::-1])
    # Out of the world counts as looked at (as the coverage window): the robot in the corner.
    mean[:3] = (0.0, 0.0, 0.0)
    image = image_of(8, coverage, empty_memory(), BOUNDS, mean, cov, observed, 0.5, 2.0)
    np.testing.assert_array_equal(image[0, :, :4], 1.0)  # behind: x < 0
    np.testing.assert_array_equal(image[0, 4:, :], 1.0)  # to the right: y < 0
    np.testing.assert_array_equal(image[0, :4, 4:], coverage[0:4, 0:4][::-1])


def test_a_wall_seen_ahead_appears_in_the_wall_channel_at_its_cell():
    walls = empty_memory()
    pose = np.array([5.0, 5.0, 0.0])
    # Two beams: one hits a wall 3.2 m ahead and 0.3 m to the left, one reaches the scan's limit (no wall).
    angles = np.array([math.atan2(0.3, 3.2), math.pi])
    scan = np.array([math.hypot(3.2, 0.3), 5.0])
    assert compiled.mark_walls(walls, pose, BOUNDS, 0.5, scan, angles, 5.0) == 1
    expected_memory = empty_memory()
    expected_memory[10, 16] = 1.0  # (8.2, 5.3): row floor(5.3 / 0.5), column floor(8.2 / 0.5)
    np.testing.assert_array_equal(walls, expected_memory)
    assert compiled.mark_walls(walls, pose, BOUNDS, 0.5, scan, angles, 5.0) == 0  # already marked

    mean, cov, observed = belief(pose, [(1.0, 1.0)], [1.0], [False])
    image = image_of(16, empty_memory(), walls, BOUNDS, mean, cov, observed, 0.5, 8.0)
    inside = image[2].copy()
    # Forward 3.2, left 0.3 in 1 m cells: row floor(8 - 0.3) = 7, column floor(3.2 + 8) = 11; outside the
    # 10 m world (x > 10, y > 10 or < 0, behind x < 0) reads 1 as in the coverage channel.
    col_x = 5.0 + (np.arange(16) - 8 + 0.5)  # the cells' centre x (forward) and y (left)
    row_y = 5.0 + (8 - np.arange(16) - 0.5)
    outside = (col_x[None, :] > 10) | (col_x[None, :] < 0) | (row_y[:, None] > 10) | (row_y[:, None] < 0)
    expected = outside.astype(np.float32)
    expected[7, 11] = 1.0
    np.testing.assert_array_equal(inside, expected)


def test_the_wall_endpoints_are_placed_at_the_pose_estimate():
    walls = empty_memory()
    estimate = np.array([3.0, 4.0, math.pi / 2])  # facing +y: a hit 2.2 m ahead is at (3.0, 6.2)
    compiled.mark_walls(walls, estimate, BOUNDS, 0.5, np.array([2.2]), np.array([0.0]), 5.0)
    assert np.argwhere(walls).tolist() == [[12, 6]]


def test_turning_the_robot_turns_the_image():
    # A quarter turn on a memory-cell corner, cells as large as the memory's: every sample stays on a cell
    # centre, so the image turns exactly: clockwise, as the world seen from a robot turning left.
    rng = np.random.default_rng(1)
    coverage = (rng.random((20, 20)) < 0.5).astype(float)
    walls = (rng.random((20, 20)) < 0.2).astype(float)
    offsets = (rng.integers(-4, 4, size=(12, 2)) + 0.5) * 0.5 + rng.uniform(-0.1, 0.1, size=(12, 2))
    landmarks = np.array([5.0, 5.0]) + offsets
    variances = rng.uniform(0.01, 1.0, 12)
    mean, cov, observed = belief((5.0, 5.0, 0.0), landmarks, variances, np.ones(12))
    before = image_of(8, coverage, walls, BOUNDS, mean, cov, observed, 0.5, 2.0)
    mean[2] = math.pi / 2
    after = image_of(8, coverage, walls, BOUNDS, mean, cov, observed, 0.5, 2.0)
    assert before[1].max() > 0 and before[2].max() > 0 and 0 < before[0].mean() < 1
    np.testing.assert_array_equal(after, np.rot90(before, k=-1, axes=(1, 2)))
    mean[2] = math.pi
    half = image_of(8, coverage, walls, BOUNDS, mean, cov, observed, 0.5, 2.0)
    np.testing.assert_array_equal(half, np.rot90(before, k=2, axes=(1, 2)))


def reference_window(memory, bounds, resolution, pose, size, extent, reduce):
    """An independent numpy reading of a robot-centred window (the conventions of the coverage window)."""
    cell = 2 * extent / size
    samples = max(1, math.ceil(cell / resolution - 1e-9))
    step = cell / samples
    x, y, theta = pose
    c, s = math.cos(theta), math.sin(theta)
    out = np.empty((size, size))
    for row in range(size):
        for col in range(size):
            left = extent - row * cell - (np.arange(samples) + 0.5) * step
            forward = -extent + col * cell + (np.arange(samples) + 0.5) * step
            f, lt = np.meshgrid(forward, left)
            fc = (x + c * f - s * lt - bounds[0]) / resolution
            fr = (y + s * f + c * lt - bounds[1]) / resolution
            inside = (fr >= 0) & (fr < memory.shape[0]) & (fc >= 0) & (fc < memory.shape[1])
            values = np.ones(f.shape)
            values[inside] = memory[fr[inside].astype(int), fc[inside].astype(int)]
            out[row, col] = reduce(values)
    return out


def drive(env, seed, steps, action_seed=0):
    observation, _ = env.reset(seed=seed)
    rng = np.random.default_rng(action_seed)
    for _ in range(steps):
        observation, *_ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
    return observation


def test_the_env_image_reads_its_memories_and_the_belief():
    env = gym.make("EKFSLAM-v0", observation=BELIEF)
    observation = drive(env, 3, 60)
    u = env.unwrapped
    o = u.config.observation
    image = observation["belief_image"]
    assert image.shape == (3, 16, 16) and image.dtype == np.float32
    assert env.observation_space.contains(observation)
    pose = u.filter.mean[:3]
    coverage = reference_window(u.coverage_memory, u.bounds, 0.5, pose, 16, o.belief_extent, np.mean)
    walls = reference_window(u.wall_memory, u.bounds, 0.5, pose, 16, o.belief_extent, np.max)
    np.testing.assert_allclose(image[0], coverage, atol=1e-6)
    np.testing.assert_array_equal(image[2], walls)
    assert u.wall_memory.sum() > 0 and 0 < image[0].mean() < 1
    # The landmark channel: every seen estimate inside the window, in its cell.
    ekf = u.filter
    c, s = math.cos(pose[2]), math.sin(pose[2])
    found = 0
    for j in np.flatnonzero(ekf.observed):
        dx, dy = ekf.mean[3 + 2 * j] - pose[0], ekf.mean[4 + 2 * j] - pose[1]
        row, col = math.floor(8 - (-s * dx + c * dy)), math.floor(c * dx + s * dy + 8)
        if 0 <= row < 16 and 0 <= col < 16:
            trace = ekf.cov[3 + 2 * j, 3 + 2 * j] + ekf.cov[4 + 2 * j, 4 + 2 * j]
            assert image[1, row, col] >= np.float32(1 / (1 + math.sqrt(trace))) > 0
            found += 1
    assert found > 0 and np.count_nonzero(image[1]) <= found
    # The last scan's hits are in the wall memory, placed from the pose estimate.
    scan = u.observation_layout.part(observation, "scan") * u.config.sensor.scan_max_range
    angles = pose[2] + np.arange(scan.size) * 2 * math.pi / scan.size
    hit = scan < u.config.sensor.scan_max_range * (1 - 1e-6)
    assert hit.any()
    cols = ((pose[0] + scan * np.cos(angles) - u.bounds[0]) / 0.5).astype(int)[hit]
    rows = ((pose[1] + scan * np.sin(angles) - u.bounds[1]) / 0.5).astype(int)[hit]
    inside = (rows >= 0) & (rows < u.wall_memory.shape[0]) & (cols >= 0) & (cols < u.wall_memory.shape[1])
    assert np.all(u.wall_memory[rows[inside], cols[inside]] == 1.0)


def test_the_image_uses_no_true_information():
    """The image is the kernel of the belief's pieces, and moving the true landmarks and the true robot while the
    belief stays the same leaves it unchanged."""
    env = gym.make("EKFSLAM-v0", observation=BELIEF)
    observation = drive(env, 5, 40)
    u = env.unwrapped
    o = u.config.observation
    ekf = u.filter
    rebuilt = image_of(16, np.array(u.coverage_memory), np.array(u.wall_memory), np.array(u.bounds),
                       np.array(ekf.mean), np.array(ekf.cov), np.array(ekf.observed), o.memory_resolution,
                       o.belief_extent)  # fmt: skip
    np.testing.assert_array_equal(rebuilt, observation["belief_image"])
    u.world.sensor.landmarks = u.world.sensor.landmarks + 3.0
    u._true_landmarks = u._true_landmarks + 3.0
    x, y, theta = u.world.pose_tuple
    u.world._pose = (x + 1.5, y - 1.0, theta + 0.7)
    again = u._observation()
    np.testing.assert_array_equal(again["belief_image"], observation["belief_image"])


def test_same_seed_same_images_and_a_copy_goes_on_alike():
    def images(env, steps):
        observation = drive(env, 7, steps, action_seed=2)
        return observation["belief_image"]

    a = gym.make("EKFSLAM-v0", observation=BELIEF, action={"kind": "primitives"})
    b = gym.make("EKFSLAM-v0", observation=BELIEF, action={"kind": "primitives"})
    for env in (a, b):
        env.reset(seed=7)
    rng = np.random.default_rng(4)
    for _ in range(8):
        action = np.int64(rng.integers(9))
        oa, *_ = a.step(action)
        ob, *_ = b.step(action)
        np.testing.assert_array_equal(oa["belief_image"], ob["belief_image"])
    twin = copy.deepcopy(a.unwrapped)
    for action in (3, 5, 1):
        oa, *_ = a.unwrapped.step(np.int64(action))
        ot, *_ = twin.step(np.int64(action))
        np.testing.assert_array_equal(oa["belief_image"], ot["belief_image"])
    assert not np.shares_memory(twin.wall_memory, a.unwrapped.wall_memory)


def test_the_flat_observation_is_unchanged_by_the_image():
    plain = gym.make("EKFSLAM-v0", observation={"kind": "dict"})
    with_image = gym.make("EKFSLAM-v0", observation=BELIEF)
    a, b = drive(plain, 9, 25), drive(with_image, 9, 25)
    assert set(b) == set(a) | {"belief_image"}
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])


def test_off_by_default_and_validated():
    env = EKFSLAMEnv()
    assert not isinstance(env.observation_space, gym.spaces.Dict)
    env.reset(seed=0)
    assert not hasattr(env, "_walls")
    with pytest.raises(ValueError, match="belief_image"):
        _ = env.wall_memory
    dict_env = EKFSLAMEnv(observation={"kind": "dict"})
    assert "belief_image" not in dict_env.observation_space.spaces
    with pytest.raises(ValueError, match="observation.belief_image"):
        EnvConfig.from_overrides(observation={"belief_image": True})
    with pytest.raises(ValueError, match="observation.belief_size"):
        EnvConfig.from_overrides(observation={**BELIEF, "belief_size": 1})
    with pytest.raises(ValueError, match="observation.belief_extent"):
        EnvConfig.from_overrides(observation={**BELIEF, "belief_extent": 0.0})
    with pytest.raises(ValueError, match="observation.belief_image"):
        EnvConfig.from_overrides(observation={"kind": "dict", "belief_image": 1})
    small = EKFSLAMEnv(observation={**BELIEF, "belief_size": 6, "belief_extent": 3.0})
    observation, _ = small.reset(seed=0)
    assert observation["belief_image"].shape == (3, 6, 6)
    assert small.observation_space["belief_image"] == gym.spaces.Box(0.0, 1.0, (3, 6, 6), np.float32)
