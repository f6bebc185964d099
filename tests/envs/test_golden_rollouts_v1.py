"""The v1 ids keep their behaviour: seeded 500-step rollouts of every registered v1 id against a recording
(``tests/golden/record_v1.py`` wrote it; the v0 ids have theirs in ``tests/envs/test_golden_rollouts.py``)."""

import numpy as np
import pytest

from tests.golden.record import rollout
from tests.golden.record_v1 import PATH, v1_ids


def test_every_v1_id_has_a_recording():
    recorded = {key.split("/")[0] for key in np.load(PATH).files}
    assert v1_ids() and set(v1_ids()) <= recorded


@pytest.mark.parametrize("env_id", v1_ids())
def test_rollout_matches_the_recording(env_id):
    recorded = np.load(PATH)
    now = rollout(env_id, "default")
    np.testing.assert_array_equal(now["flags"], recorded[f"{env_id}/flags"])
    np.testing.assert_allclose(now["observations"], recorded[f"{env_id}/observations"], rtol=0, atol=1e-5)
    np.testing.assert_allclose(now["rewards"], recorded[f"{env_id}/rewards"], rtol=1e-9, atol=1e-8)
    np.testing.assert_allclose(now["log_dets"], recorded[f"{env_id}/log_dets"], rtol=1e-10, atol=1e-8)
