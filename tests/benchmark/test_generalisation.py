"""The generalisation suite: its cases keep the family split, its shipped policies run zero-shot on their own
interface, its tables are the aggregates of its CSV, and ``ekfslam-benchmark --suite generalisation --quick``
runs end to end and resumes from its CSV. No result is asserted."""

from __future__ import annotations

import csv
import json
import math

import pytest

from ekfslam_gym.benchmark import generalisation as suite
from ekfslam_gym.cli.benchmark import main
from ekfslam_gym.envs.presets import FAMILY_IDS, family_id
from ekfslam_gym.evaluation.aggregate import aggregate
from ekfslam_gym.seeds import HELD_OUT_SEEDS, HELDOUT_FAMILIES, TRAINING_FAMILIES, family_seeds


def test_the_cases_are_every_layout_id_on_held_out_seeds_with_the_family_split():
    cases = suite.cases(4)
    by_split = {split: [c.env_id for c in cases if c.split == split] for split in suite.SPLITS}
    assert by_split["training family"] == [family_id(f) for f in TRAINING_FAMILIES]
    assert by_split["held-out family"] == [family_id(f) for f in HELDOUT_FAMILIES]
    assert by_split["large"] == ["EKFSLAM-Large-v1"]
    assert {c.env_id for c in cases} == {*FAMILY_IDS, "EKFSLAM-Large-v1"}
    for case in cases:
        assert len(case.seeds) == 4 and set(case.seeds) <= set(HELD_OUT_SEEDS)
        if case.tier is not None:
            assert case.seeds == tuple(family_seeds(FAMILY_IDS[case.env_id]).heldout)[:4]


def test_every_baseline_and_every_shipped_policy_contends():
    from ekfslam_gym.agents import BASELINES

    from ekfslam_gym.packaged import shipped_env_ids

    labels = [c.label for c in suite.contenders()]
    assert labels == [*BASELINES, *(f"ppo {env_id}" for env_id in shipped_env_ids())]


def test_a_shipped_policy_keeps_its_interface_and_leaves_the_horizon_and_reward_to_the_id():
    trained = {"action": {"kind": "primitives", "hold": 10}, "max_episode_steps": 50, "reward": {"coverage": 1.0},
               "observation": {"kind": "dict", "belief_image": True}}  # fmt: skip
    assert suite.zero_shot_settings(trained) == {
        "action": trained["action"],
        "observation": trained["observation"],
    }
    assert suite.zero_shot_settings(None) == {}


def test_the_tables_are_the_aggregates_of_the_rows():
    rows = [
        {"agent": a, "kind": "baseline", "case": c, "split": s, "seed": seed, "steps": 10, "return": 1.0,
         **{k: float(seed + (a == "b")) for k in suite.SUITE_METRICS}}
        for a in ("a", "b") for c, s in (("X", "training family"), ("Y", "held-out family")) for seed in range(6)
    ]  # fmt: skip
    summary = suite.summarise(rows)
    assert list(summary["cases"]) == ["X", "Y"] and list(summary["splits"]) == [
        "training family",
        "held-out family",
    ]
    mine = [r for r in rows if r["case"] == "X" and r["agent"] == "b"]
    assert summary["cases"]["X"]["b"] == {"episodes": 6, "metrics": aggregate(mine, suite.SUITE_METRICS)}
    text = suite.markdown(summary, about="protocol")
    assert "### `X`" in text and "| b | 6 |" in text and "seen_fraction ↑" in text and "map_log_det ↓" in text


def test_the_suite_refuses_an_agent():
    with pytest.raises(SystemExit):
        main(["--suite", "generalisation", "--agent", "frontier", "--quick"])


def test_the_quick_suite_runs_end_to_end_and_resumes_from_its_csv(tmp_path, capsys):
    assert main(["--suite", "generalisation", "--quick", "--no-progress", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert text == (tmp_path / "generalisation.md").read_text() and "A quick run" in text
    with (tmp_path / "generalisation.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    cases, contenders = suite.cases(1), suite.contenders()
    assert len(rows) == len(cases) * len(contenders)
    assert {(r["agent"], r["case"]) for r in rows} == {(a.label, c.name) for a in contenders for c in cases}
    for row in rows:
        assert int(row["steps"]) >= 1 and math.isfinite(float(row["time_to_complete"]))
        assert (
            float(row["time_to_complete"]) <= suite.QUICK_EPISODE_TIME + 1.0
        )  # a macro step's overrun at most
    summary = json.loads((tmp_path / "generalisation.json").read_text())
    assert summary["episodes"] == len(rows) and set(summary["splits"]) == set(suite.SPLITS)
    before = (tmp_path / "generalisation.csv").read_text()
    assert main(["--suite", "generalisation", "--quick", "--no-progress", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "generalisation.csv").read_text() == before  # nothing run twice
    assert capsys.readouterr().out == text
