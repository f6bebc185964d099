"""Seeded Monte Carlo through the simulator: with wheel odometry the filter's pose ANEES stays inside the chi-square
bounds under the driving that troubles the turn-drive-turn model most, a fresh command every step and slides
along the walls (``bench/consistency.py`` measures every driving, variant and odometry model)."""

import math

import numpy as np
import pytest
from scipy import stats

from ekfslam_gym.evaluation.drivings import DRIVINGS, driving_actions
from ekfslam_gym.filter import EKFSLAM
from ekfslam_gym.sim import SensorParams, WheelOdometryNoise, World, make_layout

RUNS, STEPS = 30, 100


def jittery_forward_anees(variant: str) -> tuple[np.ndarray, float]:
    """ANEES per step over RUNS seeded runs of forward driving with a fresh (v, omega) every step, the filter
    fed as the env feeds it; and the share of steps in contact with a wall."""
    sensor = SensorParams()
    nees = np.zeros((RUNS, STEPS))
    contacts = 0
    for run in range(RUNS):
        rng = np.random.default_rng([31, run])
        layout = make_layout("arena", rng, 20, width=10.0, height=10.0)
        world = World(layout, sensor=sensor, wheel_noise=WheelOdometryNoise())
        # a start the filter knows (the prior only keeps Sigma definite; the truth has no error to draw from it)
        ekf = EKFSLAM(layout.n_landmarks, motion_model="wheels", wheel_base=world.wheel_noise.wheel_base,
                      variant=variant, measurement_noise=sensor.cov, landmark_prior=100.0, pose_prior=1e-10,
                      init_mode="inverse", initial_pose=layout.start, min_range=sensor.min_range)  # fmt: skip
        readings = world.sense(rng)
        ekf.correct(readings.ids, readings.z)
        for t in range(STEPS):
            contacts += world.step(rng.uniform(0.0, 1.0), rng.uniform(-2.0, 2.0))
            odometry = world.wheel_odometry(rng)
            readings = world.sense(rng)
            ekf.predict(odometry.u, control_cov=odometry.cov)
            ekf.correct(readings.ids, readings.z)
            error = world.pose - ekf.pose
            error[2] = (error[2] + math.pi) % (2 * math.pi) - math.pi
            nees[run, t] = error @ np.linalg.solve(ekf.pose_cov, error)
    return nees.mean(axis=0), contacts / (RUNS * STEPS)


@pytest.mark.parametrize("variant", ["ekf", "fej"])
def test_wheel_odometry_filter_is_consistent_under_jittery_driving_and_wall_slides(variant):
    anees, contact = jittery_forward_anees(variant)
    assert contact > 0.05  # a 10 m arena: the robot meets its walls
    low, high = stats.chi2.ppf([0.025, 0.975], 3 * RUNS) / RUNS
    inside = np.mean((anees >= low) & (anees <= high))
    assert inside >= 0.8, f"only {inside:.0%} of steps inside [{low:.2f}, {high:.2f}]"
    assert 2.5 <= anees.mean() <= 3.5


DRIVING_RUNS, DRIVING_STEPS = 50, 200


def env_pose_anees(driving: str) -> np.ndarray:
    """Pose ANEES per step of EKFSLAM-v0's own filter (the defaults) over DRIVING_RUNS seeded episodes driven
    the ``driving`` way (``ekfslam_gym.evaluation.drivings``)."""
    import gymnasium as gym

    import ekfslam_gym  # noqa: F401

    env = gym.make("EKFSLAM-v0", max_episode_steps=DRIVING_STEPS, done_std=0.0)
    robot = env.unwrapped.config.robot
    nees = np.full((DRIVING_RUNS, DRIVING_STEPS), np.nan)
    for seed in range(DRIVING_RUNS):
        env.reset(seed=seed)
        for t, action in enumerate(
            driving_actions(driving, np.random.default_rng([seed, 0]), DRIVING_STEPS, robot)
        ):
            _, _, terminated, truncated, info = env.step(action)
            nees[seed, t] = info["pose_nees"]
            if terminated or truncated:
                break
    return nees.mean(axis=0)


@pytest.mark.parametrize("driving", DRIVINGS)
def test_default_filter_pose_anees_stays_in_its_band_under_every_driving(driving):
    """Turning in place included: 50 runs x 200 steps of each driving, seeds 0-49 (measured: 91-99 % of the
    steps inside the 95 % band, turning in place at the full rate 91 %). The share inside varies between seed
    sets even for a consistent filter (a run's NEES is correlated over tens of steps; blocks of 50 runs of 300
    gave 79-100 % for every driving), hence the margin."""
    anees = env_pose_anees(driving)
    low, high = stats.chi2.ppf([0.025, 0.975], 3 * DRIVING_RUNS) / DRIVING_RUNS
    inside = np.mean((anees >= low) & (anees <= high))
    assert inside >= 0.8, f"{driving}: only {inside:.0%} of steps inside [{low:.2f}, {high:.2f}]"
    assert 2.5 <= anees[5:].mean() <= 3.5


def test_the_first_steps_are_consistent_and_the_initial_draw_leaves_the_world_alone():
    """With ``filter.initial_draw`` the filter starts at a draw from its prior around the true start
    (``initial_estimate``), so its first
    steps' pose NEES is chi-square too: started at the truth, step 0's ANEES was 2.40 for every driving (the
    prior's 1e-10 counted with no error to match it) and turning in place slowly stayed low to step 3."""
    import gymnasium as gym

    import ekfslam_gym  # noqa: F401
    from ekfslam_gym.envs.ekfslam_env import initial_estimate

    rng = np.random.default_rng(5)
    state = rng.bit_generator.state
    draws = np.array([initial_estimate(np.zeros(3), 1e-10, np.random.default_rng(s)) for s in range(400)])
    assert np.allclose(draws.std(axis=0), 1e-5, rtol=0.15) and np.all(np.abs(draws.mean(axis=0)) < 2e-6)
    initial_estimate(np.zeros(3), 1e-10, rng)
    assert rng.bit_generator.state == state  # the world's stream is untouched

    runs, steps = 300, 4
    plain = gym.make("EKFSLAM-v0", max_episode_steps=steps)  # off by default: the filter starts at the truth
    plain.reset(seed=0)
    assert np.array_equal(plain.unwrapped.filter.pose, plain.unwrapped.world.pose)
    env = gym.make("EKFSLAM-v0", max_episode_steps=steps, filter={"initial_draw": True})
    nees = np.zeros((runs, steps))
    for seed in range(runs):
        env.reset(seed=seed)
        assert np.all(np.abs(env.unwrapped.filter.pose - env.unwrapped.world.pose) < 1e-3)
        for t in range(steps):
            nees[seed, t] = env.step(np.array([0.0, 0.5], dtype=np.float32))[4]["pose_nees"]
    low, high = stats.chi2.ppf([0.025, 0.975], 3 * runs) / runs
    anees = nees.mean(axis=0)
    assert np.all((anees >= low) & (anees <= high)), (anees, low, high)
