"""train.py and demo.py end to end at smoke size. Never asserts learning quality."""

import json
import pickle
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import demo  # noqa: E402
import train  # noqa: E402
from ekfslam_gym.training import artefacts, settings  # noqa: E402

SMOKE = ["n_steps=64", "batch_size=64", "n_envs=2", "vec_env=dummy", "eval_freq=256", "eval_episodes=1",
         "checkpoint_freq=256", "env_kwargs={max_episode_steps: 100}"]  # fmt: skip


def test_train_saves_resumes_and_evaluates(tmp_path):
    from ekfslam_gym.cli import evaluate

    out = tmp_path / "run"
    train.main(
        ["--timesteps", "512", "--out", str(out), "--seed", "3", "--no-progress", "--hyperparams", *SMOKE]
    )
    for name in ("model.zip", "model_vecnormalize.pkl", "model_config.yaml", "model_versions.json", "config.yaml",
                 "versions.json", "evaluations.npz", "best_model_config.yaml",
                 "learning_curve.png", "best_model.zip", "best_model_vecnormalize.pkl"):  # fmt: skip
        assert (out / name).is_file(), name
    assert json.loads((out / "versions.json").read_text())["stable-baselines3"] != "not installed"
    checkpoints = sorted(p.name for p in (out / "checkpoints").glob("ppo_*_steps.zip"))
    assert "ppo_512_steps.zip" in checkpoints and len(checkpoints) >= 2
    assert (out / "checkpoints" / "ppo_512_steps_rng.pkl").is_file()

    train.main(["--resume", str(out), "--timesteps", "1024", "--no-progress"])
    from stable_baselines3 import PPO

    model = PPO.load(out / "model.zip")
    assert model.num_timesteps == 1024
    with np.load(out / "evaluations.npz") as evaluations:
        assert list(evaluations["timesteps"]) == [256, 512, 768, 1024]  # the history continues
    with open(out / "model_vecnormalize.pkl", "rb") as handle:
        assert pickle.load(handle).obs_rms.count > 1024  # statistics carried over, not restarted

    status = evaluate.main(["--agent", "ppo", "--model", str(out / "model.zip"), "--seeds", "10000",
                            "--max-episode-steps", "20", "--json", "--no-progress"])  # fmt: skip
    assert status == 0


def test_resume_continues_exactly_like_an_uninterrupted_run(tmp_path):
    straight, split = tmp_path / "straight", tmp_path / "split"
    common = ["--seed", "5", "--no-progress", "--hyperparams", *SMOKE]
    train.main(["--timesteps", "768", "--out", str(straight), *common])
    train.main(["--timesteps", "512", "--out", str(split), *common])
    train.main(["--resume", str(split), "--timesteps", "768", "--no-progress"])
    from stable_baselines3 import PPO

    a = PPO.load(straight / "model.zip").policy.state_dict()
    b = PPO.load(split / "model.zip").policy.state_dict()
    # Not bit-identical (the resumed envs start new episodes), but the same number of updates from the same
    # weights: every parameter tensor is there, finite, and was trained past the checkpoint.
    assert a.keys() == b.keys()
    checkpoint = PPO.load(split / "checkpoints" / "ppo_512_steps.zip").policy.state_dict()
    assert any(not np.allclose(b[k].numpy(), checkpoint[k].numpy()) for k in b)


def test_bad_command_lines_fail_clearly(tmp_path, capsys):
    with pytest.raises(SystemExit):
        train.main(["--config", str(tmp_path / "missing.yaml")])
    assert "does not exist" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        train.main(["--resume", str(tmp_path)])
    with pytest.raises(SystemExit):
        train.main(["--hyperparams", "n_steps"])


def test_the_library_raises_settings_errors_and_the_command_line_exits_2(tmp_path, capsys):
    """The library never ends the process: a bad config file, entry or override is a ``SettingsError`` (a
    ``ValueError``) naming it, and the command line turns it into its usage error."""
    config = tmp_path / "c.yaml"
    for text, message in (("[1, 2]", "must map env ids"), ("EKFSLAM-v0: 3", "must be mappings"),
                          ("EKFSLAM-v0: {n_steps: [", "not valid YAML"),
                          ("EKFSLAM-Loop-v0: {n_steps: 64}", "has no entry for 'EKFSLAM-v0'")):  # fmt: skip
        config.write_text(text)
        with pytest.raises(settings.SettingsError, match=message) as raised:
            settings.load_entry(config, "EKFSLAM-v0")
        assert str(config) in str(raised.value) and isinstance(raised.value, ValueError)
        with pytest.raises(SystemExit) as exit_:
            train.main(["--config", str(config), "--out", str(tmp_path / "run")])
        assert exit_.value.code == 2 and message in capsys.readouterr().err
    with pytest.raises(settings.SettingsError, match="KEY=VALUE"):
        settings.parse_hyperparams(["n_steps"])
    (tmp_path / "half").mkdir()
    (tmp_path / "half" / "config.yaml").write_text("env_id: EKFSLAM-v0\nentry: {}\n")
    with pytest.raises(SystemExit) as exit_:
        train.main(["--resume", str(tmp_path / "half")])
    assert exit_.value.code == 2 and "no seed" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()


SMALL = ["n_steps=32", "batch_size=32", "n_epochs=1", "n_envs=1", "eval_episodes=1", "checkpoint_freq=0",
        "env_kwargs={max_episode_steps: 20}"]  # fmt: skip


@pytest.mark.parametrize(
    ("override", "message"),
    [("learning_rat=0.1", "unknown setting(s) ['learning_rat']"), ("n_envs=0", "n_envs must be an integer >= 1"),
     ("policy=MlpPolizy", "policy must be one of"), ("normalize={norm_obz: true}", "normalize must be"),
     ("learning_rate=fast", "learning_rate must be a number or lin_X"), ("eval_seed=10040", "held-out suite"),
     ("env_kwargs={world: {n_landmark: 3}}", "env_kwargs for EKFSLAM-v0"),
     ("policy_kwargs={activation_fn: nn.Relu}", "policy_kwargs: cannot import"),
     ("pretrain={planner: frontier}", "pretrain.planner 'frontier' demonstrates in action.kind")],
)  # fmt: skip
def test_every_setting_is_checked_before_the_run_folder_exists(tmp_path, capsys, override, message):
    out = tmp_path / "run"
    with pytest.raises(SystemExit):
        train.main(
            ["--timesteps", "32", "--out", str(out), "--no-progress", "--hyperparams", *SMALL, override]
        )
    err = capsys.readouterr().err.strip().splitlines()
    assert message in err[-1] and ": error: " in err[-1], err  # one line, after the usage
    assert not out.exists()


def test_training_seeds_in_the_held_out_suite_are_refused(tmp_path, capsys):
    with pytest.raises(SystemExit):
        train.main(
            ["--seed", "10000", "--timesteps", "32", "--out", str(tmp_path / "run"), "--hyperparams", *SMALL]
        )
    assert "seed 10000: the training envs' seeds [10000] are in the held-out suite" in capsys.readouterr().err


def test_the_run_says_when_it_rounds_and_always_evaluates(tmp_path, capsys):
    """--timesteps 40 with rollouts of 32 steps trains 64, and says so; eval_freq beyond the run's 64 steps still
    leaves best_model.zip and evaluations.npz, from one evaluation at the end; eval_freq 0 says there is none."""
    out = tmp_path / "late"
    train.main(
        ["--timesteps", "40", "--out", str(out), "--no-progress", "--hyperparams", *SMALL, "eval_freq=1000"]
    )
    err = capsys.readouterr().err
    assert "n_steps x n_envs = 32 env steps, so this run trains to 64 steps, not 40" in err
    assert "no evaluation fell inside the run" in err
    assert (out / "best_model.zip").is_file() and (out / "best_model_vecnormalize.pkl").is_file()
    with np.load(out / "evaluations.npz") as evaluations:
        assert list(evaluations["timesteps"]) == [64]
    train.main(["--timesteps", "32", "--out", str(tmp_path / "none"), "--no-progress", "--hyperparams", *SMALL,
                "eval_freq=0"])  # fmt: skip
    err = capsys.readouterr().err
    assert "no evaluation (eval_freq is 0)" in err and "rounds" not in err and "not 32" not in err
    assert not (tmp_path / "none" / "best_model.zip").exists()


def test_demo_smoke_runs_every_stage(tmp_path, capfd):
    assert demo.main(["--smoke", "--out", str(tmp_path)]) == 0
    printed = capfd.readouterr()
    assert (
        "\r" not in printed.out + printed.err
    )  # no progress bars redrawn into a log (output is not a terminal)
    for name in ("replay.png", "comparison.md", "comparison.png"):
        assert (tmp_path / name).stat().st_size > 0
    assert any((tmp_path / "gifs").glob("*.gif"))
    table = (tmp_path / "comparison.md").read_text()
    for agent in ("random", "circle", "lawnmower", "greedy", "ppo"):
        assert f"| {agent}" in table


def test_linear_schedules_in_rl_zoo_spelling():
    rate = settings.schedule("lin_3e-4")
    assert rate(1.0) == pytest.approx(3e-4) and rate(0.5) == pytest.approx(1.5e-4) and rate(0.0) == 0.0
    assert settings.schedule(0.2) == 0.2


def test_config_keeps_train_settings_out_of_the_ppo_entry(tmp_path):
    entry = settings.load_entry(Path("configs/ppo.yaml"), "EKFSLAM-v0")
    assert entry["vec_env"] == "dummy" and entry["eval_seed"] == 20_000  # merged from train_settings
    bad = tmp_path / "bad.yaml"
    bad.write_text("EKFSLAM-v0: {n_steps: 64, vec_env: dummy}\n")
    with pytest.raises(settings.SettingsError, match="train_settings"):
        settings.load_entry(bad, "EKFSLAM-v0")
    bad.write_text("EKFSLAM-v0: {n_steps: 64}\ntrain_settings: {EKFSLAM-v0: {n_stepz: 1}}\n")
    with pytest.raises(settings.SettingsError, match="unknown"):
        settings.load_entry(bad, "EKFSLAM-v0")


def test_rl_zoo3_trains_and_enjoys_on_the_project_config(tmp_path):
    """rl-zoo3 reads configs/ppo.yaml as it stands (issue: it passed project keys to PPO)."""
    pytest.importorskip("rl_zoo3")
    import subprocess
    import sys

    logs = tmp_path / "logs"
    common = ["--algo", "ppo", "--env", "EKFSLAM-v0", "--gym-packages", "ekfslam_gym", "-f", str(logs)]
    train_cmd = [sys.executable, "-m", "rl_zoo3.train", *common, "-conf", "configs/ppo.yaml", "-n", "2048",
                 "--eval-freq", "-1", "--seed", "0", "--env-kwargs", "max_episode_steps:100",
                 "--hyperparams", "n_envs:2", "n_steps:512", "batch_size:256", "n_epochs:1"]  # fmt: skip
    run = subprocess.run(train_cmd, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    assert (logs / "ppo" / "EKFSLAM-v0_1" / "EKFSLAM-v0.zip").is_file()
    enjoy_cmd = [sys.executable, "-m", "rl_zoo3.enjoy", *common, "--exp-id", "1", "--no-render", "-n", "50",
                 "--deterministic", "--env-kwargs", "max_episode_steps:100"]  # fmt: skip
    run = subprocess.run(enjoy_cmd, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]


def test_a_primitives_policy_trains_and_evaluates_on_its_own_env_settings(tmp_path):
    """The evaluator reads the action interface (and limits) from the record beside the model."""
    from ekfslam_gym.cli import evaluate

    out = tmp_path / "prim"
    overrides = [*SMOKE[:-1], "env_kwargs={action: {kind: primitives, hold: 3}, max_episode_steps: 30}"]
    train.main(["--timesteps", "256", "--out", str(out), "--seed", "1", "--no-progress", "--hyperparams",
                *overrides])  # fmt: skip
    from stable_baselines3 import PPO

    assert PPO.load(out / "model.zip").action_space.n == 9
    status = evaluate.main(["--agent", "ppo,circle", "--model", str(out / "model.zip"), "--seeds", "20000",
                            "--json", "--no-progress"])  # fmt: skip
    assert status == 0


TINY = ["n_steps=64", "batch_size=64", "n_epochs=1", "eval_freq=0", "checkpoint_freq=0"]


def test_the_belief_cnn_config_trains_and_evaluates(tmp_path):
    """configs/ppo_belief_cnn.yaml: MultiInputPolicy over the belief image through ekfslam_gym.agents.extractors.BeliefCNN
    (named by its dotted path in the config), the image left out of VecNormalize."""
    from ekfslam_gym.agents import PPOAgent
    from ekfslam_gym.agents.extractors import BeliefCNN

    from ekfslam_gym.cli import evaluate

    out = tmp_path / "cnn"
    train.main(["--config", "configs/ppo_belief_cnn.yaml", "--timesteps", "256", "--n-envs", "1", "--out",
                str(out), "--no-progress", "--hyperparams", *TINY])  # fmt: skip
    agent = PPOAgent(out / "model.zip")
    assert type(agent.model).__name__ == "PPO" and not agent.recurrent
    assert isinstance(agent.model.policy.features_extractor, BeliefCNN)
    assert agent.model.observation_space["belief_image"].shape == (3, 16, 16)
    assert "belief_image" not in agent.vecnormalize.obs_rms  # the image is left as it is, in [0, 1]
    record = artefacts.read_run(out)[2]
    assert record["policy_kwargs"]["features_extractor_class"] == "ekfslam_gym.agents.extractors.BeliefCNN"
    status = evaluate.main(["--agent", "ppo", "--model", str(out / "model.zip"), "--seeds", "20000",
                            "--max-episode-steps", "4", "--json", "--no-progress"])  # fmt: skip
    assert status == 0


def test_the_recurrent_config_trains_and_evaluates_with_its_lstm_state(tmp_path):
    """configs/ppo_lstm.yaml: train_settings algo ppo_lstm trains sb3-contrib's RecurrentPPO; the ppo agent loads
    it as such from the record beside the model, carries the LSTM state across steps and resets it at reset."""
    pytest.importorskip("sb3_contrib")
    import gymnasium as gym
    from ekfslam_gym.agents import PPOAgent
    from ekfslam_gym.agents.ppo import saved_algo

    from ekfslam_gym.cli import evaluate

    out = tmp_path / "lstm"
    train.main(["--config", "configs/ppo_lstm.yaml", "--timesteps", "256", "--n-envs", "1", "--out", str(out),
                "--no-progress", "--hyperparams", *TINY, "policy_kwargs={lstm_hidden_size: 16}"])  # fmt: skip
    assert artefacts.read_run(out)[2]["algo"] == "ppo_lstm"
    agent = PPOAgent(out / "model.zip")
    assert type(agent.model).__name__ == "RecurrentPPO" and agent.recurrent
    assert saved_algo(out / "model.zip") == "ppo_lstm"  # also without the record: from the saved policy class

    env = gym.make("EKFSLAM-v0", action={"kind": "primitives", "hold": 10}, max_episode_steps=50)
    observation, _ = env.reset(seed=20000)
    agent.reset(env, seed=20000)
    assert agent._state is None and agent._episode_start.all()
    first = agent.act(observation)
    state = agent._state
    assert state is not None and not agent._episode_start.any()
    observation, *_ = env.step(first)
    agent.act(observation)
    assert not np.array_equal(agent._state[0], state[0])  # carried forward, not restarted
    # The same as sb3-contrib's own loop: predict with the state and episode_start, on normalised observations.
    observation, _ = env.reset(seed=20000)
    agent.reset(env, seed=20000)
    states, starts, actions, expected = None, np.ones((1,), dtype=bool), [], []
    for _ in range(4):
        action = agent.act(observation)
        normalised = agent.vecnormalize.normalize_obs(observation)
        reference, states = agent.model.predict(
            normalised, state=states, episode_start=starts, deterministic=True
        )
        starts = np.zeros((1,), dtype=bool)
        actions.append(int(action))
        expected.append(int(reference))
        observation, *_ = env.step(action)
    assert actions == expected
    agent.reset(env, seed=1)
    assert agent._state is None and agent._episode_start.all()

    status = evaluate.main(["--agent", "ppo", "--model", str(out / "model.zip"), "--seeds", "20000",
                            "--max-episode-steps", "5", "--json", "--no-progress"])  # fmt: skip
    assert status == 0


def test_algo_settings_are_checked_and_dotted_classes_resolved(tmp_path):
    import torch
    from ekfslam_gym.agents.extractors import BeliefCNN

    config = tmp_path / "c.yaml"
    config.write_text("EKFSLAM-v0: {n_steps: 64}\ntrain_settings: {EKFSLAM-v0: {algo: a2c}}\n")
    with pytest.raises(settings.SettingsError, match="algo must be one of"):
        settings.load_entry(config, "EKFSLAM-v0")
    assert settings.load_entry(Path("configs/ppo.yaml"), "EKFSLAM-v0")["algo"] == "ppo"
    assert settings.load_entry(Path("configs/ppo_lstm.yaml"), "EKFSLAM-Large-v0")["algo"] == "ppo_lstm"
    from ekfslam_gym.training.settings import resolve_policy_kwargs

    resolved = resolve_policy_kwargs(
        {
            "features_extractor_class": "ekfslam_gym.agents.extractors.BeliefCNN",
            "activation_fn": "nn.ReLU",
            "net_arch": [8],
        }
    )
    assert resolved == {
        "features_extractor_class": BeliefCNN,
        "activation_fn": torch.nn.ReLU,
        "net_arch": [8],
    }
    with pytest.raises(ValueError, match="cannot import"):
        resolve_policy_kwargs({"features_extractor_class": "ekfslam_gym.agents.extractors.Missing"})


@pytest.mark.slow
def test_the_generalist_recipe_gives_the_same_model_for_the_same_seed(tmp_path):
    """configs/ppo_lstm_generalist_bc.yaml at smoke size, run twice with one seed: every stage (the planner's
    demonstrations on the mixed families, the clone, the DAgger round, PPO with cloning steps) draws from the
    seed, so the two models' weights are equal; another seed gives another model."""
    pytest.importorskip("sb3_contrib")
    import torch
    from ekfslam_gym.agents import PPOAgent

    tiny = ["n_steps=32", "batch_size=64", "n_epochs=1", "n_envs=2", "eval_freq=0", "checkpoint_freq=0",
            "policy_kwargs={net_arch: [16], lstm_hidden_size: 8, n_lstm_layers: 1, enable_critic_lstm: true}",
            "env_kwargs={action: {kind: primitives, hold: 10}, max_episode_steps: 8}",
            "pretrain={planner: frontier, episodes: 3, seed: 30000, epochs: 1, dagger_rounds: 1, "
            "dagger_episodes: 1, keep_cloning: {batches: 1, learning_rate: 3.0e-5, decay: 0.97}}"]  # fmt: skip

    def weights(seed: int, name: str) -> dict:
        out = tmp_path / name
        train.main(["--config", "configs/ppo_lstm_generalist_bc.yaml", "--env-id", "EKFSLAM-Mix-v1",
                    "--seed", str(seed), "--timesteps", "64", "--out", str(out), "--no-progress",
                    "--hyperparams", *tiny])  # fmt: skip
        return PPOAgent(out / "model.zip").model.policy.state_dict()

    first, again, other = weights(0, "a"), weights(0, "b"), weights(1, "c")
    assert first.keys() == again.keys()
    assert all(torch.equal(first[k], again[k]) for k in first)
    assert not all(torch.equal(first[k], other[k]) for k in first)
