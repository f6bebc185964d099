"""The README's results table is the benchmark's reference rows (``ekfslam_gym/benchmark/reference.json``): each
env's shipped policy and its best planner by map log det, with exactly the numbers ``ekfslam-benchmark`` compares
a user's agent with."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from ekfslam_gym.benchmark import reference_rows

README = Path(__file__).resolve().parents[2] / "README.md"
NUMBER = re.compile(r"[-−]?\d+(?:\.\d+)?(?:e[-−]?\d+)?")
ENV_IDS = ["EKFSLAM-v0", "EKFSLAM-Loop-v0", "EKFSLAM-Large-v0"]


def _numbers(cell: str) -> list[float]:
    return [float(n.replace("−", "-")) for n in NUMBER.findall(cell)]


def readme_row(env_id: str) -> tuple[list[float], str, list[float]]:
    """(shipped policy's [iqm, low, high], best planner's name, its [iqm, low, high]) of the README's results row."""
    for line in README.read_text(encoding="utf-8").splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if cells[0] == f"`{env_id}`" and len(cells) == 3:
            planner, _, interval = cells[2].partition(" ")
            return _numbers(cells[1]), planner, _numbers(interval)
    raise AssertionError(f"the README has no results row for {env_id}")


def _map_log_det(row: dict) -> list[float]:
    metric = row["metrics"]["map_log_det"]
    return [metric["iqm"], *metric["ci"]]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_readme_row_is_the_reference_rows(env_id):
    shipped, planner, planner_numbers = readme_row(env_id)
    rows = reference_rows(env_id)
    (policy,) = [row for row in rows if row["kind"] == "shipped"]
    best = min(
        (row for row in rows if row["kind"] != "shipped"),
        key=lambda row: row["metrics"]["map_log_det"]["iqm"],
    )
    assert shipped == pytest.approx(_map_log_det(policy), rel=1e-9, abs=1e-12)
    assert planner == best["agent"]
    assert planner_numbers == pytest.approx(_map_log_det(best), rel=1e-9, abs=1e-12)
