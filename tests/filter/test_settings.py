"""One filter settings object with one set of defaults, shared by ``EKFSLAM``, the env and the course replay."""

import dataclasses

import numpy as np
import pytest

from ekfslam_gym.envs.config import EnvConfig
from ekfslam_gym.filter import COURSE_SETTINGS, EKFSLAM, FilterSettings
from ekfslam_gym.filter.settings import ASSOCIATIONS, INIT_MODES, MOTION_MODELS, UPDATE_MODES, VARIANTS


def test_the_filter_and_the_env_share_one_set_of_defaults():
    assert EnvConfig().filter == FilterSettings()
    ekf = EKFSLAM(2)
    assert ekf.settings == FilterSettings()
    assert (ekf.motion_model, ekf.init_mode, ekf.landmark_prior) == ("wheels", "inverse", 100.0)
    assert np.array_equal(ekf.pose_cov, 1e-10 * np.eye(3))


def test_keyword_changes_apply_to_the_given_settings():
    ekf = EKFSLAM(2, COURSE_SETTINGS, variant="fej", landmark_prior=50.0)
    assert ekf.settings == dataclasses.replace(COURSE_SETTINGS, variant="fej", landmark_prior=50.0)
    assert (ekf.motion_model, ekf.init_mode, ekf.variant) == ("odometry", "course", "fej")
    assert ekf.log_det == -np.inf  # the course's zero pose prior
    with pytest.raises(TypeError, match=r"unknown filter setting\(s\) \['motion'\]; known: \['motion_model'"):
        EKFSLAM(2, motion="wheels")
    with pytest.raises(TypeError, match="FilterSettings"):
        EKFSLAM(2, {"motion_model": "wheels"})


def test_an_initial_pose_covariance_replaces_the_scalar_prior():
    ekf = EKFSLAM(1, initial_pose_cov=[1e-4, 2e-4, 0.09])
    assert np.array_equal(ekf.pose_cov, np.diag([1e-4, 2e-4, 0.09]))


@pytest.mark.parametrize(
    ("field", "choices"),
    [
        ("motion_model", MOTION_MODELS),
        ("variant", VARIANTS),
        ("init_mode", INIT_MODES),
        ("update", UPDATE_MODES),
        ("association", ASSOCIATIONS),
    ],
)
def test_each_choice_is_checked_once_with_one_message(field, choices):
    for choice in choices:
        FilterSettings(**{field: choice})
    message = f"filter.{field} must be {'|'.join(choices)}, got 'nope'"
    for build in (
        lambda: FilterSettings(**{field: "nope"}),
        lambda: EKFSLAM(2, **{field: "nope"}),
        lambda: EnvConfig.from_overrides(filter={field: "nope"}),
    ):
        with pytest.raises(ValueError) as error:
            build()
        assert str(error.value) == message


@pytest.mark.parametrize(
    "changes",
    [
        dict(iterations=0),
        dict(landmark_prior=0.0),
        dict(landmark_prior=float("inf")),
        dict(pose_prior=-1.0),
        dict(pose_prior=[1.0, 1.0, 1.0]),
        dict(resync_every=-1),
        dict(gate_prob=1.0),
        dict(gate_prob=0.999, new_gate_prob=0.99),
        dict(confirm_steps=True),
    ],
)
def test_bad_settings_raise_naming_the_field(changes):
    with pytest.raises(ValueError, match=f"filter.{next(iter(changes))}|filter.new_gate_prob"):
        FilterSettings(**changes)


def test_the_env_needs_a_positive_pose_prior_the_filter_does_not():
    assert FilterSettings(pose_prior=0.0).pose_prior == 0.0
    with pytest.raises(ValueError, match=r"filter.pose_prior must be > 0, got 0.0"):
        EnvConfig.from_overrides(filter={"pose_prior": 0.0})


def test_the_course_settings_are_the_course_filter():
    assert COURSE_SETTINGS == FilterSettings(
        motion_model="odometry", init_mode="course", landmark_prior=1000.0, pose_prior=0.0
    )
