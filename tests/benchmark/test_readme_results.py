"""The README's results tables are the benchmark's reference rows (``ekfslam_gym/benchmark/reference.json``):
``ekfslam-benchmark`` compares a user's agent with exactly the numbers the README shows."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from ekfslam_gym.benchmark import reference_rows

README = Path(__file__).resolve().parents[2] / "README.md"
COLUMNS = {
    "map log det": "map_log_det",
    "landmark RMSE (m)": "landmark_rmse",
    "landmarks seen": "seen_fraction",
    "wall contacts": "collisions",
    "loop closures": "loop_closures",
}
NUMBER = re.compile(r"[-−]?\d+(?:\.\d+)?(?:e[-−]?\d+)?")


def _numbers(cell: str) -> list[float]:
    return [float(n.replace("−", "-")) for n in NUMBER.findall(cell)]


def readme_table(env_id: str) -> dict[str, dict[str, list[float]]]:
    """{agent row: {metric: [iqm, ci low, ci high]}} of the README's table under ``**<env_id>**``."""
    lines = README.read_text(encoding="utf-8").splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(f"**{env_id}**"))
    table = [line for line in lines[start + 1 :] if line.startswith("|")]
    rows = []
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        rows.append(line)
    assert rows, f"no table under **{env_id}**"
    header = [cell.strip().rstrip(" ↓↑").strip() for cell in table[0].strip("|").split("|")]
    out = {}
    for line in rows[2:]:
        cells = [cell.strip() for cell in line.strip("|").split("|")]
        out[cells[0]] = {COLUMNS[name]: _numbers(cell) for name, cell in zip(header[1:], cells[1:])}
    return out


@pytest.mark.parametrize("env_id", ["EKFSLAM-v0", "EKFSLAM-Loop-v0", "EKFSLAM-Large-v0"])
def test_the_readme_tables_are_the_reference_rows(env_id):
    table = readme_table(env_id)
    rows = reference_rows(env_id)
    assert len(table) == len(rows) <= 6
    for row in rows:
        name = "shipped PPO" if row["kind"] == "shipped" else row["agent"]
        assert name in table, f"{env_id}: the README has no row {name!r}"
        for metric, printed in table[name].items():
            reference = row["metrics"][metric]
            expected = [reference["iqm"], *reference["ci"]]
            assert printed == pytest.approx(expected, rel=1e-9, abs=1e-12), (env_id, name, metric)
