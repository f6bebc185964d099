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
V0 = [i for i in REGISTERED if i.endswith("-v0")]
# The step limit each v0 id was registered with when its version was given; a new limit is a new version.
STEP_LIMITS = {"EKFSLAM-v0": 500, "EKFSLAM-Loop-v0": 800, "EKFSLAM-Large-v0": 1000}
# The v1 ids' episode length in simulated time (s), registered without a step limit; the family ids' (EKFSLAM-v1 and
# EKFSLAM-Loop-v1 among them) and the mixed id's is their tier's (the default tier's here).
EPISODE_TIMES = {"EKFSLAM-Large-v1": 600.0}


def test_every_registered_id_is_versioned_and_pinned_by_a_golden_rollout():
    from tests.golden.record_v1 import PATH, v1_ids

    recorded = np.load(ROOT / "tests" / "golden" / "rollouts.npz").files
    recorded_v1 = np.load(PATH).files
    assert sorted(ENV_IDS) == V0 and sorted(V0 + v1_ids()) == REGISTERED
    for env_id in REGISTERED:
        assert re.fullmatch(r"EKFSLAM(-[A-Za-z]+)?-v\d+", env_id), env_id
        if env_id in V0:
            assert f"{PREFIX['default']}{env_id}/observations" in recorded, f"{env_id} has no golden rollout"
        else:
            assert f"{env_id}/observations" in recorded_v1, f"{env_id} has no golden rollout"


def test_every_registered_id_keeps_its_step_limit():
    from ekfslam_gym.envs.presets import DEFAULT_TIER, FAMILY_IDS, MIX_ID, TIER_EPISODE_TIME

    assert sorted(STEP_LIMITS) == V0
    for env_id, limit in STEP_LIMITS.items():
        assert gym.spec(env_id).max_episode_steps == limit
    times = {**EPISODE_TIMES, **dict.fromkeys([*FAMILY_IDS, MIX_ID], TIER_EPISODE_TIME[DEFAULT_TIER])}
    for env_id in REGISTERED:
        if env_id not in V0:
            assert gym.spec(env_id).max_episode_steps is None
            config = gym.make(env_id).unwrapped.config
            assert config.max_episode_steps is None and config.episode_time == times[env_id]


def test_every_id_has_a_description_and_a_version_history():
    from ekfslam_gym.envs.presets import DESCRIPTIONS, VERSION_HISTORY, id_base

    for env_id in REGISTERED:
        assert DESCRIPTIONS[env_id]
        versions = [release.version for release in VERSION_HISTORY[id_base(env_id)]]
        assert env_id.rpartition("-")[2] in versions and versions == sorted(
            versions, key=lambda v: int(v[1:])
        )


def test_the_changelog_has_the_packages_version():
    changelog = (ROOT / "CHANGELOG.md").read_text()
    assert f"## [{ekfslam_gym.__version__}]" in changelog
    assert "## [0.1.0]" in changelog
