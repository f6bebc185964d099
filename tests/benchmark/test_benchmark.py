"""ekfslam-benchmark: the reference rows are docs/results.md's held-out rows, and the command runs the protocol
beside them (only --quick runs here; the full frontier check is in the report of the change)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import gymnasium as gym
import pytest

from ekfslam_gym import benchmark
from ekfslam_gym.cli.benchmark import main

ROOT = Path(__file__).resolve().parents[2]
REGISTERED = sorted(
    i for i in gym.registry if i.startswith("EKFSLAM") and i.endswith("-v0")
)  # with reference rows


def test_every_registered_env_has_the_baselines_and_its_shipped_policy_as_reference_rows():
    for env_id in REGISTERED:
        rows = benchmark.reference_rows(env_id)
        assert [r["agent"] for r in rows] == ["random", "circle", "lawnmower", "greedy", "frontier", "ppo"]
        assert [r["kind"] for r in rows].count("shipped") == 1
        for row in rows:
            assert row["episodes"] == 50 and {"map_log_det", "landmark_rmse"} <= set(row["metrics"])
            for metric in row["metrics"].values():
                assert metric["ci"][0] <= metric["iqm"] <= metric["ci"][1]


def _numbers(line: str) -> list[tuple[float, float, float]]:
    """Every ``IQM [lo, hi]`` cell of a table row, as numbers."""
    return [tuple(float(v) for v in m) for m in re.findall(r"\| (\S+) \[(\S+), (\S+)\]", line + "|")]


def test_each_reference_row_is_a_row_of_the_results_page():
    """The JSON holds the numbers the published record prints for the row it names (docs/results.md, or the
    research log where results.md shows fewer columns), so tables made from it agree."""
    pages = [ROOT / "docs" / "results.md", *sorted((ROOT / "docs").glob("research-log*.md"))]
    text = "\n".join(page.read_text() for page in pages)
    lines = text.replace("−", "-").replace("**", "").splitlines()
    for env_id in REGISTERED:
        for row in benchmark.reference_rows(env_id):
            wanted = [(m["iqm"], *m["ci"]) for m in row["metrics"].values()]
            found = [
                line
                for line in lines
                if line.startswith(f"| {row['source']['row']} |") and _numbers(line) == wanted
            ]
            assert found, (
                f"{env_id}: no row {row['source']['row']!r} with these numbers in the results or the log"
            )


def test_reproduces_compares_at_the_tables_precision():
    row = {
        "metrics": {"map_log_det": {"iqm": -564.0, "ci": [-569.0, -559.0]}, "ate": {"iqm": 0.1, "ci": [0, 1]}}
    }
    result = {"metrics": {"map_log_det": {"iqm": -564.3, "ci": [-569.4, -558.6]}}}
    assert benchmark.reproduces(result, row) == {"map_log_det": True}
    result["metrics"]["map_log_det"]["iqm"] = -565.0
    assert benchmark.reproduces(result, row) == {"map_log_det": False}


def test_a_quick_run_sits_beside_the_reference_rows(tmp_path, capsys):
    assert (
        main(
            [
                "--agent",
                "random",
                "--env-ids",
                "EKFSLAM-v0",
                "--quick",
                "--no-progress",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert (
        "| **random** (this run) | 5 |" in text
        and "| frontier (reference) | 50 | -564 [-569, -559] |" in text
    )
    report = json.loads((tmp_path / "benchmark.json").read_text())
    assert report["seeds"] == "10000-10004" and report["quick"] and list(report["results"]) == ["EKFSLAM-v0"]
    assert report["results"]["EKFSLAM-v0"]["reproduces"] is None  # a quick run is not compared
    assert (tmp_path / "benchmark.md").read_text() == text


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        ([], "give --agent NAME"),
        (["--agent", "teleport"], "unknown agent 'teleport'"),
        (["--agent", "random", "--env-ids", "EKFSLAM-v9"], "unknown env id"),
        (
            ["--model", str(ROOT / "models" / "ppo_EKFSLAM-Loop-v0.zip"), "--env-ids", "EKFSLAM-v0"],
            "the model was trained on EKFSLAM-Loop-v0, not EKFSLAM-v0",
        ),  # fmt: skip
        (
            ["--agent", "greedy", "--model", str(ROOT / "models" / "ppo_EKFSLAM-v0.zip")],
            "--model is a ppo policy",
        ),
        (["--agent", "frontier-waypoint"], "--agent frontier-waypoint acts in action.kind waypoint"),
    ],
)
def test_bad_arguments_are_named(argv, message, capsys):
    with pytest.raises(SystemExit):
        main([*argv, "--quick"])
    assert message in capsys.readouterr().err
