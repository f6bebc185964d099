"""Refactors change no behaviour: seeded 500-step rollouts of every registered id against values recorded
before the package was reorganised (``tests/golden/record.py`` wrote them)."""

from pathlib import Path

import numpy as np
import pytest

from tests.golden.record import ENV_IDS, PREFIX, SETTINGS, rollout

GOLDEN = Path(__file__).resolve().parents[1] / "golden" / "rollouts.npz"


@pytest.mark.parametrize("setting", SETTINGS)
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_rollout_matches_the_recording(env_id, setting):
    recorded = np.load(GOLDEN)
    key = f"{PREFIX[setting]}{env_id}"
    now = rollout(env_id, setting)
    np.testing.assert_array_equal(now["flags"], recorded[f"{key}/flags"])
    # The world's motion does not depend on the filter, so only rounding can differ: hold everything tightly.
    np.testing.assert_allclose(now["observations"], recorded[f"{key}/observations"], rtol=0, atol=1e-5)
    np.testing.assert_allclose(now["rewards"], recorded[f"{key}/rewards"], rtol=1e-9, atol=1e-8)
    np.testing.assert_allclose(now["log_dets"], recorded[f"{key}/log_dets"], rtol=1e-10, atol=1e-8)
