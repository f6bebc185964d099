"""Unknown data association: the gates, nearest neighbour and JCBC on cases with known answers, landmark
initialisation and forgetting with an exact running log det, and the env's wiring and counts."""

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from scipy import stats

import ekfslam_gym  # noqa: F401  (registers the env ids)
from ekfslam_gym import compiled
from ekfslam_gym.envs.config import EnvConfig
from ekfslam_gym.filter import COURSE_SETTINGS, EKFSLAM, AssociationSettings
from ekfslam_gym.filter.association import chi2_even_ppf, gate_table
from ekfslam_gym.filter.models import range_bearing
from ekfslam_gym.sim.sensor import RangeBearingSensor, SensorParams

Q = np.diag([0.05**2, 0.01**2])
NEAREST = AssociationSettings("nearest", confirm_steps=0)
JCBC = AssociationSettings("jcbc", confirm_steps=0)


def _reading(pose, landmark):
    return range_bearing(np.asarray(pose, float), np.asarray(landmark, float), 1e-3)[0]


def _mapped(landmarks, n_slots, heading_var=0.0, slots=None):
    """A filter at the origin that has read ``landmarks`` once, exactly, into ``slots`` (default 0, 1, ...),
    then lost heading certainty (a zero-motion prediction with heading variance ``heading_var``)."""
    ekf = EKFSLAM(
        n_slots,
        COURSE_SETTINGS,
        pose_prior=1e-8,
        measurement_noise=Q,
        landmark_prior=100.0,
        init_mode="inverse",
    )
    slots = list(range(len(landmarks))) if slots is None else slots
    ekf.correct(slots, [_reading((0, 0, 0), lm) for lm in landmarks])
    if heading_var:
        ekf.predict([0.0, 0.0, 0.0], motion_cov=np.diag([1e-8, 1e-8, heading_var]))
    return ekf


@pytest.mark.parametrize("prob", [0.5, 0.95, 0.99, 0.999])
@pytest.mark.parametrize("dof", [2, 4, 10, 60, 400])
def test_even_chi2_quantiles_match_scipy(prob, dof):
    assert chi2_even_ppf(prob, dof) == pytest.approx(stats.chi2.ppf(prob, dof), rel=1e-10)


def test_gate_table_covers_the_pairings_asked_for():
    table = gate_table(0.99, 70)
    assert len(table) >= 70
    np.testing.assert_allclose(table[:5], stats.chi2.ppf(0.99, 2 * np.arange(1, 6)), rtol=1e-10)
    with pytest.raises(ValueError, match="gate"):
        gate_table(1.0, 3)


def test_two_landmarks_closer_than_the_gate_confuse_nearest_and_not_jcbc():
    # Two landmarks 0.06 rad apart at 4 m; the filter's heading is off by 0.06 rad (true heading -0.06), so the
    # first landmark's reading lands exactly on the second's prediction. Alone, both readings fit the second
    # landmark best; jointly only the pairing A-A, B-B explains both by one heading error.
    d = 0.06
    a, b = (4.0, 0.0), (4.0 * math.cos(d), 4.0 * math.sin(d))
    ekf = _mapped([a, b], 4, heading_var=0.05**2)
    readings = [_reading((0, 0, -d), a), _reading((0, 0, -d), b)]
    assert readings[0] == pytest.approx(_reading((0, 0, 0), b))
    gate = stats.chi2.ppf(0.99, 2)
    assert np.all(ekf.associate(readings, NEAREST) == [1, 1])
    assert np.all(ekf.associate(readings, JCBC) == [0, 1])
    # Both readings pass the individual gate of both landmarks: the ambiguity is real.
    S = _innovation_cov(ekf, 0)
    assert (2 * d) ** 2 / S[1, 1] < gate


def _innovation_cov(ekf, slot):
    j = 3 + 2 * slot
    _, hx, hm = range_bearing(np.asarray(ekf.mean[:3]), np.asarray(ekf.mean[j : j + 2]), 1e-3)
    H = np.zeros((2, ekf.state_size))
    H[:, :3] = hx
    H[:, j : j + 2] = hm
    return H @ ekf.cov @ H.T + Q


def test_clutter_next_to_a_landmark_takes_it_under_nearest_only():
    ekf = _mapped([(3.0, 1.0), (-2.0, 4.0)], 4)
    true = _reading((0, 0, 0), (3.0, 1.0))
    clutter = true + np.array([0.08, 0.01])  # inside the landmark's gate, beside its true reading
    S = _innovation_cov(ekf, 0)
    nu = clutter - true
    assert nu @ np.linalg.solve(S, nu) < stats.chi2.ppf(0.99, 2)
    readings = [clutter, true]
    assert np.all(ekf.associate(readings, NEAREST) == [0, 0])
    assert np.all(ekf.associate(readings, JCBC) == [-1, 0])
    result = ekf.copy().correct_unknown(readings, JCBC)
    assert np.all(result.slots == [-1, 0]) and not result.new.any()  # clutter discarded, not a new landmark


def test_a_reading_far_from_every_landmark_starts_one_in_the_first_free_slot():
    ekf = _mapped([(3.0, 1.0), (-2.0, 4.0)], 5, slots=[1, 3])
    far = _reading((0, 0, 0), (1.0, -4.0))
    known = _reading((0, 0, 0), (3.0, 1.0))
    result = ekf.correct_unknown([known, far], JCBC)
    assert np.all(result.slots == [1, 0]) and np.all(result.new == [False, True])
    assert np.all(ekf.observed == [True, True, False, True, False])
    np.testing.assert_allclose(ekf.landmarks[0], (1.0, -4.0), atol=1e-6)
    # With no free slot left, a new landmark is dropped.
    full = _mapped([(3.0, 1.0), (-2.0, 4.0)], 2)
    assert np.all(full.correct_unknown([known, far], JCBC).slots == [0, -1])


@pytest.mark.parametrize("method", ["nearest", "jcbc"])
def test_gating_rejects_an_outlier_and_only_a_far_one_is_new(method):
    settings = AssociationSettings(method)
    ekf = _mapped([(3.0, 1.0)], 3)
    true = _reading((0, 0, 0), (3.0, 1.0))
    info = np.linalg.inv(_innovation_cov(ekf, 0))
    inside, between = stats.chi2.ppf([0.9, 0.995], 2)
    assert stats.chi2.ppf(0.99, 2) < between < stats.chi2.ppf(0.999, 2)

    def offset(d2):  # a range error of Mahalanobis distance d2
        return true + np.array([math.sqrt(d2 / info[0, 0]), 0.0])

    assert ekf.associate([offset(inside)], settings)[0] == 0
    assert ekf.associate([offset(between)], settings)[0] == -1
    result = ekf.copy().correct_unknown([offset(between)], settings)
    assert result.slots[0] == -1 and not result.new[0] and result.delta == 0.0
    result = ekf.copy().correct_unknown([offset(100.0)], settings)
    assert result.slots[0] == 1 and result.new[0]


@pytest.mark.parametrize("method", ["nearest", "jcbc"])
@pytest.mark.parametrize("variant", ["ekf", "fej", "iekf"])
def test_running_log_det_stays_exact_through_association_initialisation_and_forgetting(method, variant):
    rng = np.random.default_rng(7)
    landmarks = rng.uniform(-6, 6, (12, 2))
    ekf = EKFSLAM(14, COURSE_SETTINGS, pose_prior=1e-6, measurement_noise=Q, landmark_prior=100.0, variant=variant,
                  resync_every=0)  # fmt: skip
    pose = np.zeros(3)
    forgotten = new = 0
    for _ in range(60):
        control = np.array([rng.uniform(-0.3, 0.3), rng.uniform(0, 0.3), rng.uniform(-0.3, 0.3)])
        pose = np.array([
            pose[0] + control[1] * math.cos(pose[2] + control[0]),
            pose[1] + control[1] * math.sin(pose[2] + control[0]),
            pose[2] + control[0] + control[2],
        ])  # fmt: skip
        ekf.predict(control, motion_cov=np.diag([1e-4, 1e-4, 1e-5]))
        readings = [_reading(pose, lm) for lm in landmarks if np.hypot(*(lm - pose[:2])) < 5.0]
        readings = [z + rng.normal(0, [0.05, 0.01]) for z in readings]
        readings += [np.array([rng.uniform(0.5, 5.0), rng.uniform(-math.pi, math.pi)])]  # clutter
        before = ekf.log_det
        result = ekf.correct_unknown(readings, AssociationSettings(method, confirm_steps=2))
        forgotten += len(result.forgotten)
        new += int(result.new.sum())
        exact = np.linalg.slogdet(ekf.cov)[1]
        assert ekf.log_det == pytest.approx(exact, abs=1e-8 * max(1.0, abs(exact)))
        assert ekf.log_det - before == pytest.approx(result.delta, abs=1e-8 * max(1.0, abs(exact)))
    assert forgotten > 0 and new > forgotten


def test_forget_returns_a_slot_to_the_prior():
    ekf = _mapped([(3.0, 1.0), (-2.0, 4.0)], 3)
    delta = ekf.forget(0)
    assert not ekf.observed[0] and ekf.observed[1]
    np.testing.assert_array_equal(ekf.landmarks[0], 0.0)
    assert ekf.cov[3, 3] == ekf.cov[4, 4] == 100.0 and np.all(ekf.cov[3:5, np.r_[0:3, 5:9]] == 0)
    assert ekf.log_det == pytest.approx(np.linalg.slogdet(ekf.cov)[1], abs=1e-9)
    assert delta > 0
    with pytest.raises(IndexError):
        ekf.forget(3)


def test_bad_association_arguments_raise():
    ekf = _mapped([(3.0, 1.0)], 2)
    with pytest.raises(
        ValueError, match=r"association.kind must be one of \['jcbc', 'nearest'\].*EKFSLAM.correct"
    ):
        ekf.associate([[1.0, 0.0]], AssociationSettings("known"))
    with pytest.raises(TypeError, match="AssociationSettings"):
        ekf.associate([[1.0, 0.0]], "jcbc")
    with pytest.raises(ValueError, match="finite"):
        ekf.correct_unknown([[np.nan, 0.0]], JCBC)


@pytest.mark.parametrize(
    "changes, message",
    [
        (dict(kind="icp"), "association.kind must be known|nearest|jcbc, got 'icp'"),
        (dict(gate_prob=1.5), r"association.gate_prob must be in \(0, 1\), got 1.5"),
        (dict(new_gate_prob=0.9), "association.new_gate_prob must be >= association.gate_prob, got 0.9"),
        (dict(confirm_steps=-1), "association.confirm_steps must be an integer >= 0, got -1"),
        (dict(confirm_steps=True), "association.confirm_steps must be an integer >= 0, got True"),
    ],
)
def test_bad_association_settings_raise_naming_the_field(changes, message):
    with pytest.raises(ValueError, match=message):
        AssociationSettings(**changes)


def test_the_env_section_hands_out_the_association_settings():
    config = EnvConfig.from_overrides(
        filter={"association": "nearest", "gate_prob": 0.95, "confirm_steps": 2}
    )
    assert config.filter.association_settings == AssociationSettings("nearest", 0.95, confirm_steps=2)
    assert EnvConfig().filter.association_settings == AssociationSettings()


def test_tally_counts_false_and_missed_associations():
    truth = np.array([3, -1, 5, 7, 4, -1], dtype=np.int64)
    z = np.arange(12, dtype=float).reshape(6, 2)
    slots = np.array([0, 1, -1, 2, 4, -1], dtype=np.int64)
    new = np.array([False, False, False, True, False, False])
    slot_truth = np.array([3, 4, -1, -1, -1, 9], dtype=np.int64)
    observed = np.array([True, True, True, False, True, True])
    true_landmarks = np.arange(20, dtype=float).reshape(10, 2)
    slot_landmarks = np.zeros((6, 2))
    valid = np.zeros(6, dtype=bool)
    false, missed, read, read_z = compiled.tally_associations(
        truth, z, slots, new, np.array([5], dtype=np.int64), observed, slot_truth, true_landmarks,
        slot_landmarks, valid,
    )  # fmt: skip
    # clutter on slot 1 and landmark 4 on the clutter-started slot 4 are false; landmark 5 is missed.
    assert (false, missed) == (2, 1)
    np.testing.assert_array_equal(read, [0, 1, 2, 4])
    np.testing.assert_array_equal(read_z, z[[0, 1, 3, 4]])
    np.testing.assert_array_equal(slot_truth, [3, 4, 7, -1, 4, -1])  # 7 new, 4 adopted, 5 forgotten
    np.testing.assert_array_equal(slot_landmarks[[2, 4]], true_landmarks[[7, 4]])
    np.testing.assert_array_equal(valid, [True, True, True, False, True, False])


def test_the_sensor_drops_and_invents_readings_only_when_asked():
    landmarks = np.array([[2.0, 0.0], [3.0, 1.0], [4.0, -1.0]])
    walls = np.zeros((0, 4))
    plain = RangeBearingSensor(landmarks, walls, 0.1)
    a, b = np.random.default_rng(3), np.random.default_rng(3)
    ids, z = plain.sense((0.0, 0.0, 0.0), a)
    assert np.all(ids == [0, 1, 2])
    b.standard_normal((3, 2))  # the defaults draw exactly the readings' noise, nothing more
    np.testing.assert_array_equal(a.random(4), b.random(4))
    params = SensorParams(detection_prob=0.5, clutter_rate=3.0)
    noisy = RangeBearingSensor(landmarks, walls, 0.1, params)
    rng = np.random.default_rng(0)
    counts, clutter = np.zeros(3), []
    for _ in range(2000):
        ids, z = noisy.sense((0.0, 0.0, 0.0), rng)
        for i in ids[ids >= 0]:
            counts[i] += 1
        clutter.append(z[ids < 0])
        assert np.all(ids[: np.count_nonzero(ids >= 0)] >= 0)  # clutter last
    clutter = np.concatenate(clutter)
    np.testing.assert_allclose(counts / 2000, 0.5, atol=0.05)
    assert len(clutter) / 2000 == pytest.approx(3.0, rel=0.05)
    assert clutter[:, 0].min() >= params.min_range and clutter[:, 0].max() <= params.max_range
    assert np.abs(clutter[:, 1]).max() <= 0.5 * params.fov
    with pytest.raises(ValueError, match="detection_prob"):
        SensorParams(detection_prob=0.0)
    with pytest.raises(ValueError, match="clutter_rate"):
        SensorParams(clutter_rate=-1.0)


@pytest.mark.parametrize(
    "overrides, field",
    [
        (dict(filter={"association": "icp"}), "filter.association"),
        (dict(filter={"gate_prob": 1.0}), "filter.gate_prob"),
        (dict(filter={"gate_prob": 0.99, "new_gate_prob": 0.9}), "filter.new_gate_prob"),
        (dict(filter={"confirm_steps": -1}), "filter.confirm_steps"),
        (dict(sensor={"detection_prob": 1.5}), "detection_prob"),
    ],
)
def test_bad_association_config_names_the_field(overrides, field):
    with pytest.raises(ValueError, match=field):
        EnvConfig.from_overrides(**overrides)


def _drive(env, steps, seed=0):
    rng = np.random.default_rng(seed)
    info = None
    for t in range(steps):
        if t % 10 == 0:
            action = rng.uniform(-1, 1, 2).astype(np.float32)
        _, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    return info


def _recount(steps):
    """False and missed associations recounted from each step's association (true ids, slots, new, forgotten),
    with the env's rules (``ekfslam_gym.envs.association_truth``), from a fresh ``slot_truth``."""
    slot_truth, false, missed = None, 0, 0
    for truth, slots, new, forgotten, before in steps:
        slot_truth = before.copy() if slot_truth is None else slot_truth
        slot_truth[forgotten] = -1
        for t, s, started in zip(truth, slots, new):
            if s < 0:
                missed += t >= 0
            elif started:
                slot_truth[s] = t
            else:
                false += t < 0 or slot_truth[s] != t
                if t >= 0 and slot_truth[s] < 0:
                    slot_truth[s] = t
    return false, missed


@pytest.mark.parametrize(("association", "clutter_rate"), [("jcbc", 0.5), ("nearest", 2.0)])
def test_env_with_unknown_association_and_clutter_passes_the_checker_and_counts(
    monkeypatch, association, clutter_rate
):
    """The env's counts are the sums of what every step's association did (recounted here from the readings'
    true ids and the filter's slots); dense clutter under nearest neighbour makes false associations."""
    steps = []
    tally = compiled.tally_associations

    def spy(truth, z, slots, new, forgotten, observed, slot_truth, *rest):
        steps.append((truth.copy(), slots.copy(), new.copy(), forgotten.copy(), slot_truth.copy()))
        return tally(truth, z, slots, new, forgotten, observed, slot_truth, *rest)

    env = gym.make(
        "EKFSLAM-v0",
        filter={"association": association},
        sensor={"clutter_rate": clutter_rate, "detection_prob": 0.9},
    )
    check_env(env.unwrapped, skip_render_check=True)
    monkeypatch.setattr(compiled, "tally_associations", spy)
    _, info = env.reset(seed=3)
    assert info["false_associations"] == 0 and info["missed_associations"] == 0
    info = _drive(env, 150)
    u = env.unwrapped
    assert len(steps) == 151  # the reset's readings and every step's
    assert (info["false_associations"], info["missed_associations"]) == _recount(steps)
    if association == "nearest":
        assert info["false_associations"] > 0
    truth = u.slot_truth
    held = u.filter.observed & (truth >= 0)
    assert held.any()
    # The map RMSE compares each slot with the true landmark it holds.
    errors = np.asarray(u.filter.landmarks)[held] - u.true_landmarks[truth[held]]
    assert info["map_rmse"] == pytest.approx(math.sqrt(np.mean(np.sum(errors**2, axis=1))))
    assert info["map_rmse"] < 0.5
    ids, _ = info["readings"]
    assert np.all(ids >= 0) and np.all(u.filter.observed[ids])  # the slots the filter used


@pytest.mark.parametrize("sensor", [{}, {"detection_prob": 0.8}, {"clutter_rate": 1.0}])
def test_known_association_counts_nothing(sensor):
    env = gym.make("EKFSLAM-v0", sensor=sensor)
    env.reset(seed=1)
    info = _drive(env, 80)
    assert info["false_associations"] == 0 and info["missed_associations"] == 0
    np.testing.assert_array_equal(env.unwrapped.slot_truth, np.arange(30))
    assert np.all(info["readings"].ids >= 0)


def test_evaluation_reports_the_counts_and_scores_slots_by_the_landmark_they_hold():
    from ekfslam_gym.evaluation.episode_metrics import ASSOCIATION_KEYS, METRIC_KEYS
    from ekfslam_gym.evaluation.rollout import evaluate_agent

    class Held:
        name = "held"

        def reset(self, env, seed=None):
            self.rng, self.t = np.random.default_rng(seed), 0

        def act(self, observation):
            if self.t % 10 == 0:
                self.action = self.rng.uniform(-1, 1, 2).astype(np.float32)
            self.t += 1
            return self.action

    kwargs = {"filter": {"association": "jcbc"}, "sensor": {"clutter_rate": 0.5}}
    (row,) = evaluate_agent(Held(), "EKFSLAM-v0", [4], kwargs, max_episode_steps=120)
    assert set(METRIC_KEYS + ASSOCIATION_KEYS) <= set(row)
    assert row["landmark_rmse"] < 0.5 and 0 < row["seen_fraction"] <= 1
    (known,) = evaluate_agent(Held(), "EKFSLAM-v0", [4], None, max_episode_steps=120)
    assert not set(ASSOCIATION_KEYS) & set(known)
