"""The observation: coverage and coarse windows, the layout of its parts, the scan agents read."""

import numpy as np
import pytest

from ekfslam_gym.envs import EKFSLAMEnv


def test_coverage_window_is_robot_centred_and_turns_with_the_heading():
    from ekfslam_gym.envs.kernels import mark_coverage
    from ekfslam_gym.envs.observation import make_memory

    env = EKFSLAMEnv(world={"layout_kwargs": {"width": 40.0, "height": 40.0}})
    obs, _ = env.reset(seed=0)
    grid = env.config.observation.grid
    window = env.observation_layout.part(obs, "coverage").reshape(grid, grid)
    pose = env.filter.pose
    bounds, memory_now = env.bounds, env.coverage_memory
    # Rebuild the memory from the one pose the sensor has looked from, and read the window by hand.
    memory = make_memory(bounds, 0.5)
    mark_coverage(memory, np.array(pose), bounds, 0.5, env.config.sensor.max_range, env.config.sensor.fov)
    assert np.array_equal(memory, memory_now)
    centre = grid // 2
    assert window[centre, centre + 2] == 1.0  # 4 m straight ahead: inside the 6 m, 180 degree footprint
    ahead_left = pose[:2] + 4.0 * np.array([np.cos(pose[2] + 0.5), np.sin(pose[2] + 0.5)])
    assert memory_now[int((ahead_left[1] - bounds[1]) / 0.5), int((ahead_left[0] - bounds[0]) / 0.5)]
    behind = pose[:2] - 4.0 * np.array([np.cos(pose[2]), np.sin(pose[2])])
    inside = bounds[0] < behind[0] < bounds[2] and bounds[1] < behind[1] < bounds[3]
    assert window[centre, centre - 2] == (0.0 if inside else 1.0)  # behind: not looked at (or outside)


def test_coarse_window_holds_the_fraction_looked_at_and_can_be_disabled():
    env = EKFSLAMEnv()
    obs, _ = env.reset(seed=2)
    coarse = obs[-25:].reshape(5, 5)
    assert coarse.min() >= 0.0 and coarse.max() <= 1.0
    assert np.any((coarse > 0.0) & (coarse < 1.0))  # partly looked-at cells are fractions, not flags
    assert (
        coarse[0].min() == 1.0 or coarse[:, 0].min() == 1.0 or coarse[-1].min() == 1.0
    )  # 20 m reaches outside
    plain = EKFSLAMEnv(observation={"coarse_grid": 0})
    assert plain.observation_space.shape == (139,)
    np.testing.assert_array_equal(plain.reset(seed=2)[0], obs[:-25])


@pytest.mark.parametrize(
    "observation, n_beams",
    [({}, 16), ({"k_nearest": 3, "grid": 5, "coarse_grid": 3}, 7), ({"kind": "dict", "coarse_grid": 0}, 16)],
)
def test_observation_layout_is_where_the_spaces_and_the_kernel_put_each_part(observation, n_beams):
    from ekfslam_gym.envs.kernels import fill_observation
    from ekfslam_gym.envs.observation import (
        LANDMARK_FEATURES,
        PARTS,
        ObservationLayout,
        observation_constants,
    )

    env = EKFSLAMEnv(observation=observation, sensor={"n_beams": n_beams})
    cfg = env.config
    layout = env.observation_layout
    assert layout == ObservationLayout.from_config(cfg.observation, cfg.sensor)
    # The slices tile the vector in PARTS order; the offsets say the same, absent parts being empty spans.
    present = [name for name in PARTS if name in layout.slices]
    assert list(layout.slices) == present == list(layout.sizes)
    assert ("coverage_coarse" in present) == (cfg.observation.coarse_grid > 0)
    stops = [0] + [layout.slices[name].stop for name in present]
    assert [layout.slices[name].start for name in present] == stops[:-1] and stops[-1] == layout.size
    for i, name in enumerate(PARTS):
        span = layout.offsets[i + 1] - layout.offsets[i]
        assert span == (layout.sizes[name] if name in present else 0)
    assert layout.sizes["landmarks"] == LANDMARK_FEATURES * cfg.observation.k_nearest
    assert layout.sizes["scan"] == n_beams and layout.sizes["coverage"] == cfg.observation.grid**2
    # The spaces are the layout's.
    space = env.observation_space
    if cfg.observation.kind == "dict":
        assert sorted(space.spaces) == sorted(present)  # gymnasium sorts a Dict's keys
        assert all(space[name].shape == (layout.sizes[name],) for name in present)
    else:
        assert space.shape == (layout.size,)

    obs, _ = env.reset(seed=6)
    for _ in range(20):
        obs, *_ = env.step(np.array([0.6, 0.4]))
    flat = np.concatenate([obs[name] for name in present]) if isinstance(obs, dict) else obs
    part = {name: layout.part(obs, name) for name in present}
    np.testing.assert_array_equal(flat[layout.slices["scan"]], part["scan"])
    # What the kernel wrote where the layout says: the scan, the pose, the time left, the landmark slots.
    scan = np.minimum(env.world.scan() / cfg.sensor.scan_max_range, 1.0).astype(np.float32)
    np.testing.assert_array_equal(part["scan"], scan)
    pose = env.filter.pose
    np.testing.assert_allclose(part["pose"][2:], [np.sin(pose[2]), np.cos(pose[2])], atol=1e-6)
    np.testing.assert_allclose(part["pose_cov"], np.log(np.diag(env.filter.pose_cov)) / 10, atol=1e-5)
    assert part["globals"][1] == pytest.approx(env.filter.observed.mean())
    assert part["globals"][2] == pytest.approx(1.0 - 20 / cfg.max_episode_steps)
    slots = part["landmarks"].reshape(-1, LANDMARK_FEATURES)
    assert slots[:, 0].sum() == min(env.filter.observed.sum(), cfg.observation.k_nearest)
    # Every entry is written: the kernel on a NaN-filled vector reproduces the observation exactly.
    ekf = env.filter
    out = np.full(layout.size, np.nan, dtype=np.float32)
    fill_observation(
        out, layout.offsets, observation_constants(cfg.observation, cfg.sensor), ekf.mean, ekf.cov,
        ekf.observed, ekf.log_det, ekf.pose_cov_given_map, env.world.scan(), env.coverage_memory, env.bounds,
        1.0 - 20 / cfg.max_episode_steps,
    )  # fmt: skip
    np.testing.assert_array_equal(out, flat)


def test_agents_read_the_scan_through_the_env_layout():
    from ekfslam_gym.agents.base import wall_scan

    for observation in ({"coarse_grid": 0, "k_nearest": 2}, {"kind": "dict"}):
        env = EKFSLAMEnv(observation=observation, sensor={"n_beams": 9})
        obs, _ = env.reset(seed=1)
        truth = np.minimum(env.world.scan(), env.config.sensor.scan_max_range)
        np.testing.assert_allclose(wall_scan(env, obs), truth, rtol=1e-6)


def test_layout_rejects_bad_sizes():
    from ekfslam_gym.envs.observation import ObservationLayout

    with pytest.raises(ValueError, match="n_beams"):
        ObservationLayout(8, 0, 9)
    with pytest.raises(ValueError, match="kind"):
        ObservationLayout(8, 16, 9).space("image")
