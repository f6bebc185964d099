"""A user's own agent enters every command that takes ``--agent`` as ``module:Class`` or ``module:function``
(``ekfslam_gym.agents.make_agent``)."""

from __future__ import annotations

import json
import sys

import pytest
from ekfslam_gym.agents import is_agent_name, make_agent

MODULE = """
import numpy as np


class Bounce:
    name = "bounce"

    def __init__(self, speed=1.0):
        self.speed = speed

    def reset(self, env, seed=None):
        self.turn = 0.0

    def act(self, observation):
        return np.array([self.speed, self.turn], dtype=np.float32)


def slow():
    return Bounce(speed=0.2)


class NoAct:
    def reset(self, env, seed=None):
        pass
"""


@pytest.fixture
def user_module(tmp_path, monkeypatch):
    """``myagents.py`` in the current folder, which is not on the path (as under a console script)."""
    (tmp_path / "myagents.py").write_text(MODULE)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", str(tmp_path))])
    monkeypatch.delitem(sys.modules, "myagents", raising=False)
    return tmp_path


def test_a_class_and_a_factory_build_agents(user_module):
    assert is_agent_name("myagents:Bounce") and not is_agent_name("myagents") and not is_agent_name(":x")
    assert make_agent("myagents:Bounce", speed=0.5).speed == 0.5
    assert make_agent("myagents:slow").speed == 0.2


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("myagents:NoAct", "has no act method"),
        ("myagents:Missing", "module 'myagents' has no 'Missing'"),
        ("nosuchmodule:Agent", "cannot import 'nosuchmodule'"),
        ("bouncer", "unknown agent 'bouncer'; choose one of .* or give module:Class"),
    ],
)
def test_a_bad_agent_is_named(user_module, name, message):
    with pytest.raises(ValueError, match=message):
        make_agent(name)


def test_evaluate_compares_a_users_agent_with_a_baseline(user_module, capsys):
    from ekfslam_gym.cli.evaluate import main

    argv = ["--agent", "myagents:Bounce,circle", "--agent-kwargs", '{"myagents:Bounce": {"speed": 0.5}}']
    assert main([*argv, "--seeds", "0", "--max-episode-steps", "3", "--json", "--no-progress"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert set(result) == {"myagents:Bounce", "circle"}
    assert result["myagents:Bounce"]["metrics"]["path_length"]["iqm"] > 0
