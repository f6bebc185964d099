"""The env-version policy (docs/versioning.md) has teeth: every registered id is pinned by the golden rollouts
(tests/envs/test_golden_rollouts.py) and by its registered step limit here, so a change of behaviour under an id
fails until it gets a new version; the changelog has a section for the package's version."""

from __future__ import annotations

import re
from pathlib import Path

import gymnasium as gym
import numpy as np

import ekfslam_gym
from tests.golden.record import ENV_IDS, PREFIX

ROOT = Path(__file__).resolve().parents[2]
REGISTERED = sorted(i for i in gym.registry if i.startswith("EKFSLAM"))
# The step limit each id was registered with when its version was given; a new limit is a new version.
STEP_LIMITS = {"EKFSLAM-v0": 500, "EKFSLAM-Loop-v0": 800, "EKFSLAM-Large-v0": 1000}


def test_every_registered_id_is_versioned_and_pinned_by_a_golden_rollout():
    recorded = np.load(ROOT / "tests" / "golden" / "rollouts.npz").files
    assert sorted(ENV_IDS) == REGISTERED
    for env_id in REGISTERED:
        assert re.fullmatch(r"EKFSLAM(-[A-Za-z]+)?-v\d+", env_id), env_id
        assert f"{PREFIX['default']}{env_id}/observations" in recorded, f"{env_id} has no golden rollout"


def test_every_registered_id_keeps_its_step_limit():
    assert sorted(STEP_LIMITS) == REGISTERED
    for env_id, limit in STEP_LIMITS.items():
        assert gym.spec(env_id).max_episode_steps == limit


def test_the_changelog_has_the_packages_version():
    changelog = (ROOT / "CHANGELOG.md").read_text()
    assert f"## [{ekfslam_gym.__version__}]" in changelog
    assert "## [0.1.0]" in changelog
