"""One filter settings object with one set of defaults, shared by ``EKFSLAM``, the env and the course replay;
the association's settings apart, and the env's section holding both."""

import dataclasses

import numpy as np
import pytest

from ekfslam_gym.envs.config import EnvConfig, FilterConfig
from ekfslam_gym.filter import COURSE_SETTINGS, EKFSLAM, AssociationSettings, FilterSettings
from ekfslam_gym.filter.settings import (
    ASSOCIATIONS,
    INIT_MODES,
    KNOWN_START_POSE_PRIOR,
    MOTION_MODELS,
    UPDATE_MODES,
    VARIANTS,
)


def test_the_filter_and_the_env_share_one_set_of_defaults():
    assert EnvConfig().filter.settings == FilterSettings()
    assert EnvConfig().filter.association_settings == AssociationSettings()
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


def test_each_association_is_checked_once_with_one_message():
    for kind in ASSOCIATIONS:
        assert AssociationSettings(kind).kind == kind
        assert EnvConfig.from_overrides(filter={"association": kind}).filter.association_settings.kind == kind
    choices = "|".join(ASSOCIATIONS)
    with pytest.raises(ValueError, match=f"^association.kind must be {choices}, got 'nope'$"):
        AssociationSettings("nope")
    with pytest.raises(ValueError, match=f"^filter.association must be {choices}, got 'nope'$"):
        EnvConfig.from_overrides(filter={"association": "nope"})


@pytest.mark.parametrize(
    "changes",
    [
        dict(iterations=0),
        dict(landmark_prior=0.0),
        dict(landmark_prior=float("inf")),
        dict(pose_prior=-1.0),
        dict(pose_prior=[1.0, 1.0, 1.0]),
        dict(resync_every=-1),
    ],
)
def test_bad_settings_raise_naming_the_field(changes):
    with pytest.raises(ValueError, match=f"filter.{next(iter(changes))}"):
        FilterSettings(**changes)


def test_the_filter_settings_hold_only_what_the_filter_reads():
    # The association's settings are each call's (correct_unknown), the initial draw the env's.
    for name in ("association", "gate_prob", "new_gate_prob", "confirm_steps", "initial_draw"):
        assert name not in {f.name for f in dataclasses.fields(FilterSettings)}
        with pytest.raises(TypeError, match=rf"unknown filter setting\(s\) \['{name}'\]"):
            EKFSLAM(2, **{name: FilterConfig.__dataclass_fields__[name].default})


def test_the_env_section_is_flat_and_gives_each_part_its_own_object():
    config = EnvConfig.from_overrides(
        filter={"variant": "fej", "association": "jcbc", "gate_prob": 0.95, "initial_draw": True}
    )
    assert config.filter.settings == FilterSettings(variant="fej")
    assert config.filter.association_settings == AssociationSettings("jcbc", gate_prob=0.95)
    assert config.filter.initial_draw
    # The env's section passed whole to EKFSLAM gives it its filter fields and nothing more.
    assert EKFSLAM(2, config.filter).settings == config.filter.settings
    assert EnvConfig.from_overrides(**config.to_dict()) == config
    assert "association" in config.to_dict()["filter"] and "initial_draw" in config.to_dict()["filter"]


@pytest.mark.parametrize(
    "changes, message",
    [
        (dict(association="icp"), "filter.association must be known|nearest|jcbc, got 'icp'"),
        (dict(gate_prob=1.0), r"filter.gate_prob must be in \(0, 1\), got 1.0"),
        (
            dict(gate_prob=0.999, new_gate_prob=0.99),
            "filter.new_gate_prob must be >= filter.gate_prob, got 0.99",
        ),
        (dict(confirm_steps=-1), "filter.confirm_steps must be an integer >= 0, got -1"),
        (dict(initial_draw=1), "filter.initial_draw must be true or false, got 1"),
    ],
)
def test_the_env_section_names_its_own_keys(changes, message):
    with pytest.raises(ValueError, match=message):
        EnvConfig.from_overrides(filter=changes)


def test_the_env_needs_a_positive_pose_prior_the_filter_does_not():
    assert FilterSettings(pose_prior=0.0).pose_prior == 0.0
    with pytest.raises(ValueError, match=r"filter.pose_prior must be > 0, got 0.0"):
        EnvConfig.from_overrides(filter={"pose_prior": 0.0})


def test_the_course_settings_are_the_course_filter():
    assert COURSE_SETTINGS == FilterSettings(
        motion_model="odometry", init_mode="course", landmark_prior=1000.0, pose_prior=0.0
    )
    assert FilterSettings().pose_prior == KNOWN_START_POSE_PRIOR == 1e-10
