"""The consistency report: map NEES and NIS on cases with known answers, a seeded Monte-Carlo check that the
default filter's NIS sits in its chi-squared band under random driving, and the command line."""

from __future__ import annotations

import json
from functools import partial

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401
from ekfslam_gym.evaluation.consistency import innovation_nis, map_nees, run_consistency
from ekfslam_gym.filter import COURSE_SETTINGS, EKFSLAM


def test_map_nees_of_a_diagonal_covariance():
    mean = np.zeros(3 + 2 * 3)
    mean[3:5] = [1.0, 2.0]
    mean[7:9] = [5.0, 5.5]
    cov = np.diag(np.r_[np.ones(3), [0.25, 0.25, 9.0, 9.0, 4.0, 1.0]])
    truth = np.array([[0.5, 2.0], [0.0, 0.0], [5.0, 4.5]])
    observed = np.array([True, False, True])
    value, dof = map_nees(mean, cov, observed, truth)
    assert dof == 4
    assert value == pytest.approx(0.5**2 / 0.25 + 0.0 + 0.0 + 1.0**2 / 1.0)
    assert map_nees(mean, cov, np.zeros(3, bool), truth) == (0.0, 0)


def test_nis_matches_the_dense_textbook_form():
    """nu^T (H Sigma H^T + Q)^-1 nu with H built by finite differences of the measurement function."""
    ekf = EKFSLAM(2, COURSE_SETTINGS, init_mode="inverse", pose_prior=0.01, landmark_prior=100.0)
    ekf.correct([0, 1], [[3.0, 0.4], [4.0, -0.7]])
    ekf.predict([0.1, 0.5, -0.05], control_cov=np.diag([1e-3, 4e-3, 1e-3]))
    z = np.array([[2.7, 0.45], [3.8, -0.6]])
    value, dof = innovation_nis(ekf, np.array([0, 1]), z, ekf.measurement_noise)
    assert dof == 4

    def h(state):
        out = []
        for j in range(2):
            d = state[3 + 2 * j : 5 + 2 * j] - state[:2]
            out += [np.hypot(*d), np.arctan2(d[1], d[0]) - state[2]]
        return np.array(out)

    mu, cov = ekf.mean.copy(), ekf.cov.copy()
    H = np.empty((4, mu.size))
    for k in range(mu.size):
        step = np.zeros(mu.size)
        step[k] = 1e-6
        H[:, k] = (h(mu + step) - h(mu - step)) / 2e-6
    nu = z.ravel() - h(mu)
    nu[1::2] = (nu[1::2] + np.pi) % (2 * np.pi) - np.pi
    S = H @ cov @ H.T + np.kron(np.eye(2), ekf.measurement_noise)
    assert value == pytest.approx(float(nu @ np.linalg.solve(S, nu)), rel=1e-6)
    # a reading of a landmark not yet in the map is not an innovation
    fresh = EKFSLAM(2, COURSE_SETTINGS, init_mode="inverse", pose_prior=0.01)
    assert innovation_nis(fresh, np.array([1]), z[:1], fresh.measurement_noise) == (0.0, 0)


def test_default_filter_nis_and_map_nees_sit_in_their_bands_under_random_driving():
    """Seeded (20 runs x 80 steps); the margins allow a few steps outside the 95 % bands."""
    from ekfslam_gym.agents import make_agent

    run = run_consistency(
        lambda: gym.make("EKFSLAM-v0", max_episode_steps=80), make_agent("random"), range(20), 80, "random"
    )
    assert run.fraction_inside("nis") >= 0.85
    assert run.fraction_inside("map_nees") >= 0.85
    assert 0.7 < float(np.nanmedian(run.normalised("nis"))) < 1.4
    assert (run.dofs["pose_nees"] == 60).all()  # 20 runs x 3 dof at every step


def test_consistency_command_line(tmp_path, capsys):
    from ekfslam_gym.cli.consistency import main

    plot = tmp_path / "c.png"
    argv = ["--agents", "random,circle", "--filters", "ekf,iekf", "--seeds", "0-1", "--steps", "20"]
    assert main([*argv, "--json", "--plot", str(plot)]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert [r["label"] for r in result["runs"]] == [
        "random / ekf",
        "random / iekf",
        "circle / ekf",
        "circle / iekf",
    ]
    assert all(0.0 <= r["nis"]["inside"] <= 1.0 for r in result["runs"])
    assert plot.stat().st_size > 0
    with pytest.raises(SystemExit):
        main(["--filters", "ukf"])


class _Sequence:
    """A fixed sequence of primitive indices, one per call of act."""

    def __init__(self, choices):
        self.choices = list(choices)

    def reset(self, env, seed=None):
        self.calls = 0

    def act(self, observation):
        choice = self.choices[self.calls % len(self.choices)]
        self.calls += 1
        return choice


def test_decisions_repeated_per_control_step_drive_as_the_macro_action_does():
    """decide_every N on hold 1 reaches the same world and belief as hold N, and asks the agent every N steps."""
    choices = [1, 4, 4, 7, 0]
    macro = gym.make("EKFSLAM-v0", action={"kind": "primitives", "hold": 10})
    macro.reset(seed=3)
    for choice in choices:
        macro.step(choice)
    agent = _Sequence(choices)

    def factory():
        return gym.make("EKFSLAM-v0", action={"kind": "primitives", "hold": 1}, max_episode_steps=50)

    run = run_consistency(factory, agent, [3], 50, "seq", decide_every=10)
    assert agent.calls == len(choices)
    assert run.dofs["pose_nees"].tolist() == [3] * 50  # every control step sampled
    with pytest.raises(ValueError, match="decide_every"):
        run_consistency(factory, agent, [3], 5, "seq", decide_every=0)
    single = factory()
    single.reset(seed=3)
    for choice in choices:
        for _ in range(10):
            single.step(choice)
    np.testing.assert_array_equal(single.unwrapped.world.pose, macro.unwrapped.world.pose)
    np.testing.assert_array_equal(single.unwrapped.filter.mean, macro.unwrapped.filter.mean)


def test_an_agent_is_refused_in_an_interface_it_does_not_act_in(capsys):
    # run_consistency steps the env itself, so the check is there too, not only in the evaluator's episodes
    from ekfslam_gym.agents import make_agent

    from ekfslam_gym.cli.consistency import main

    with pytest.raises(SystemExit) as exit_info:
        main(
            [
                "--agents",
                "frontier",
                "--env-kwargs",
                '{"action": {"kind": "waypoint", "hold": 1}}',
                "--steps",
                "3",
            ]
        )
    assert exit_info.value.code == 2
    assert "--agents frontier: agent 'frontier' acts in action.kind 'velocity'" in capsys.readouterr().err
    factory = partial(gym.make, "EKFSLAM-v0", action={"kind": "primitives", "hold": 1}, max_episode_steps=3)
    with pytest.raises(ValueError, match="this env takes 'primitives' actions"):
        run_consistency(factory, make_agent("frontier"), [0], 3, "frontier")
    result = run_consistency(factory, make_agent("frontier-primitives"), [0], 3, "frontier-primitives")
    assert result.label == "frontier-primitives" and result.runs == 1
