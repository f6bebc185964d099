"""Refactors of the baselines change no behaviour: their actions on seeded episodes against a recording."""

from pathlib import Path

import numpy as np
import pytest

from tests.golden.record_agents import AGENT_NAMES, ENV_IDS, actions

GOLDEN = Path(__file__).resolve().parents[1] / "golden" / "agents.npz"


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("agent_name", AGENT_NAMES)
def test_actions_match_the_recording(agent_name, env_id):
    recorded = np.load(GOLDEN)[f"{env_id}/{agent_name}"]
    np.testing.assert_allclose(actions(agent_name, env_id), recorded, rtol=0, atol=1e-6)
