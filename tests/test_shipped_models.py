"""The shipped policies: one per registered env, each beside its statistics, training record and versions, and
each runs through ``ekfslam-evaluate --agent ppo --model models/<file>.zip --env-id <id>`` on the
settings its record names (action interface and observation included). No quality is asserted here."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import pytest
import yaml

import ekfslam_gym  # noqa: F401  (registers the ids)

MODELS = Path(__file__).resolve().parent.parent / "models"
IDS = sorted(spec_id for spec_id in gym.registry if spec_id.startswith("EKFSLAM"))


def test_every_registered_env_has_a_shipped_policy():
    assert IDS, "no EKFSLAM ids registered"
    for env_id in IDS:
        stem = MODELS / f"ppo_{env_id}"
        for suffix in (".zip", "_vecnormalize.pkl", "_config.yaml", "_versions.json"):
            assert Path(f"{stem}{suffix}").is_file(), f"{stem}{suffix} missing"
        record = yaml.safe_load(Path(f"{stem}_config.yaml").read_text())
        assert record["env_id"] == env_id
        assert "action" in record["entry"]["env_kwargs"]


@pytest.mark.parametrize("env_id", IDS)
def test_each_shipped_policy_runs_through_evaluate(env_id, capsys):
    from ekfslam_gym.cli.evaluate import main

    model = MODELS / f"ppo_{env_id}.zip"
    argv = [
        "--env-id",
        env_id,
        "--agent",
        "ppo",
        "--model",
        str(model),
        "--seeds",
        "0",
        "--max-episode-steps",
    ]
    assert main([*argv, "3", "--json", "--no-progress"]) == 0
    captured = capsys.readouterr()
    result = json.loads(captured.out)
    assert result["agent"] == "ppo" and result["episodes"] == 1
    assert "trained with env_kwargs" not in captured.err  # it ran on its own recorded settings


@pytest.mark.parametrize("env_id", IDS)
def test_each_shipped_policy_runs_through_the_consistency_report(env_id, capsys):
    """The report builds the policy's env from its record (the v0 policy reads the belief image), not only the
    recorded action interface."""
    from ekfslam_gym.cli.consistency import main

    model = MODELS / f"ppo_{env_id}.zip"
    argv = ["--env-id", env_id, "--agents", "ppo", "--model", str(model), "--filters", "ekf", "--seeds", "0"]
    assert main([*argv, "--steps", "12", "--json"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert [r["label"] for r in result["runs"]] == ["ppo / ekf"]
