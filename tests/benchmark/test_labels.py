"""The benchmark's rows say whose they are and how far they can be compared."""

from __future__ import annotations

import sys

from ekfslam_gym import benchmark
from ekfslam_gym.cli.benchmark import main

AGENT = """
import numpy as np

from ekfslam_gym.agents import Agent


class StandStill(Agent):
    name = "stand-still"

    def act(self, observation):
        return np.zeros(2, dtype=np.float32)
"""


def test_your_agent_is_labelled_by_its_name(tmp_path, monkeypatch, capsys):
    (tmp_path / "mine_for_labels.py").write_text(AGENT)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "mine_for_labels", raising=False)
    argv = ["--agent", "mine_for_labels:StandStill", "--env-ids", "EKFSLAM-v0", "--quick", "--no-progress"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "| **stand-still** (this run) | 5 |" in text
    assert "mine_for_labels:StandStill" not in text
    assert "not comparable with this --quick run" in text


def test_reference_rows_say_which_package_made_them_and_whether_they_compare():
    made = benchmark.reference()["package"]["ekfslam-gym"]
    full, quick = benchmark.reference_note("EKFSLAM-v0"), benchmark.reference_note("EKFSLAM-v0", quick=True)
    assert f"made by ekfslam-gym {made} on EKFSLAM-v0" in full and "; comparable: yes" in full
    assert "not comparable" in quick and "not comparable" not in full
