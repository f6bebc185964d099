"""Every benchmark script runs (at its smoke size), so none breaks silently. Timings are never asserted."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXPECTED = {
    "actions.py": "/ velocity",
    "association.py": "jcbc / known",
    "belief_image.py": "dict + belief_image",
    "consistency.py": "median ANEES",
    "decisions.py": "time per act() call",
    "ekf.py": "landmarks",
    "env.py": "CartPole-v1",
    "sim.py": "step = physics",
    "graph.py": "bearing-range",
    "layouts.py": "placement grid",
    "startup.py": "ratio EKFSLAM-v0 / CartPole-v1",
    "team.py": "robot-step cost",
    "train.py": "env steps/s",
}


def test_every_bench_script_is_covered():
    assert sorted(p.name for p in (ROOT / "bench").glob("*.py")) == sorted(EXPECTED)


@pytest.mark.parametrize("script", sorted(EXPECTED))
def test_bench_script_runs_at_smoke_size(script):
    if script == "train.py":
        pytest.importorskip("stable_baselines3")
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    result = subprocess.run(
        [sys.executable, str(ROOT / "bench" / script), "--smoke"], cwd=ROOT, env=env, capture_output=True,
        text=True, timeout=300,
    )  # fmt: skip
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-3000:]
    assert EXPECTED[script] in result.stdout, result.stdout[-2000:]
