"""Progress bars only on a terminal: a log, a pipe or CI gets no carriage-return redraws (make demo, train.py,
evaluate). The demo's own output is checked in tests/training/test_train.py."""

import io

import pytest


class _Stream(io.StringIO):
    def __init__(self, terminal: bool) -> None:
        super().__init__()
        self.terminal = terminal

    def isatty(self) -> bool:
        return self.terminal


@pytest.mark.parametrize("terminal", [True, False])
def test_evaluation_draws_its_bar_only_on_a_terminal(monkeypatch, terminal):
    from ekfslam_gym.agents import make_agent

    from ekfslam_gym.evaluation.rollout import evaluate_agent

    stream = _Stream(terminal)
    monkeypatch.setattr("sys.stderr", stream)
    evaluate_agent(make_agent("random"), seeds=[20000, 20001], max_episode_steps=5, progress=True)
    assert ("\r" in stream.getvalue()) == terminal


@pytest.mark.parametrize("terminal", [True, False])
def test_training_asks_for_its_bar_only_on_a_terminal(monkeypatch, tmp_path, terminal):
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO

    import train

    asked = []
    learn = PPO.learn

    def spy(self, *args, progress_bar=False, **kwargs):
        asked.append(progress_bar)
        return learn(self, *args, progress_bar=False, **kwargs)

    monkeypatch.setattr(PPO, "learn", spy)
    monkeypatch.setattr("sys.stdout", _Stream(terminal))
    train.main(["--timesteps", "64", "--out", str(tmp_path / "run"), "--hyperparams", "n_steps=32",
                "batch_size=32", "n_envs=2", "eval_freq=0", "checkpoint_freq=0"])  # fmt: skip
    assert asked == [terminal]
