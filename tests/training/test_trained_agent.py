"""``ekfslam-train --trained-agent``: a new run that starts from a saved policy, at smoke size. Never asserts
learning quality."""

import pickle

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import train  # noqa: E402
from ekfslam_gym.packaged import resolve_config  # noqa: E402
from ekfslam_gym.training import settings  # noqa: E402
from ekfslam_gym.training.run import train as train_run  # noqa: E402
from ekfslam_gym.training.trained_agent import check_trained_agent  # noqa: E402

SMOKE = ["n_steps=64", "batch_size=64", "n_envs=2", "vec_env=dummy", "eval_freq=0", "checkpoint_freq=0",
         "env_kwargs={max_episode_steps: 50}"]  # fmt: skip


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """A PPO policy of 256 steps on EKFSLAM-v0, with its statistics and record: the model to start from."""
    out = tmp_path_factory.mktemp("base") / "run"
    train.main(
        ["--timesteps", "256", "--out", str(out), "--seed", "3", "--no-progress", "--hyperparams", *SMOKE]
    )
    return out / "model.zip"


def weights(path):
    from stable_baselines3 import PPO

    return {k: v.numpy().copy() for k, v in PPO.load(path).policy.state_dict().items()}


def fine_tune(base, out, seed=4, extra=()):
    train.main(["--timesteps", "256", "--out", str(out), "--seed", str(seed), "--no-progress",
                "--trained-agent", str(base), "--hyperparams", *SMOKE, *extra])  # fmt: skip
    return out / "model.zip"


def test_a_run_starts_from_the_trained_weights_and_statistics(base, tmp_path):
    from stable_baselines3 import PPO

    tuned = fine_tune(base, tmp_path / "tuned")
    fresh = tmp_path / "fresh"
    train.main(
        ["--timesteps", "256", "--out", str(fresh), "--seed", "4", "--no-progress", "--hyperparams", *SMOKE]
    )
    start, after, scratch = weights(base), weights(tuned), weights(fresh / "model.zip")
    # 256 steps are two PPO updates (a linear schedule makes the last one 0): the tuned weights stay near the base model's, and far
    # nearer to them than a fresh network of the same seed is.
    near = sum(float(np.abs(after[k] - start[k]).sum()) for k in start)
    far = sum(float(np.abs(scratch[k] - start[k]).sum()) for k in start)
    assert 0 < near < far / 10
    assert PPO.load(tuned).num_timesteps == 256  # a new run: its own step count
    with open(base.with_name("model_vecnormalize.pkl"), "rb") as handle:
        base_count = pickle.load(handle).obs_rms.count
    with open(tuned.with_name("model_vecnormalize.pkl"), "rb") as handle:
        assert pickle.load(handle).obs_rms.count > base_count  # statistics carried over, not restarted
    record = (tmp_path / "tuned" / "config.yaml").read_text()
    assert "--trained-agent" in record and str(base) in record  # the command line repeats the run


def test_one_seed_and_one_trained_agent_give_one_model(base, tmp_path):
    a, b = fine_tune(base, tmp_path / "a"), fine_tune(base, tmp_path / "b")
    c = fine_tune(base, tmp_path / "c", seed=5)
    first, again, other = weights(a), weights(b), weights(c)
    assert all(np.array_equal(first[k], again[k]) for k in first)
    assert not all(np.array_equal(first[k], other[k]) for k in first)


@pytest.mark.parametrize(
    ("extra", "message"),
    [(["--hyperparams", *SMOKE, "normalize=false"], "does not normalise observations"),
     (["--hyperparams", *SMOKE, "policy_kwargs={net_arch: [8]}"], "a trained network keeps its shape"),
     (["--hyperparams", *SMOKE, "env_kwargs={action: {kind: primitives}}"], "its action space is"),
     (["--config", "ppo_lstm", "--hyperparams", *SMOKE], "trained with algo 'ppo'")],
)  # fmt: skip
def test_what_cannot_continue_the_model_is_refused_before_the_run_folder_exists(base, tmp_path, capsys, extra,
                                                                               message):  # fmt: skip
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as exit_:
        train.main(
            ["--timesteps", "64", "--out", str(out), "--no-progress", "--trained-agent", str(base), *extra]
        )
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and message in err[-1] and ": error: " in err[-1], err
    assert not out.exists()


def test_a_missing_model_a_resume_and_the_library_fail_clearly(base, tmp_path, capsys):
    out = tmp_path / "run"
    with pytest.raises(SystemExit):
        train.main(["--out", str(out), "--trained-agent", str(tmp_path / "nothing.zip")])
    err = capsys.readouterr().err
    assert "neither a saved model" in err and "nothing.zip is not a file" in err
    with pytest.raises(SystemExit):
        train.main(["--resume", str(base.parent), "--trained-agent", str(base)])
    assert "give one of them" in capsys.readouterr().err
    entry = settings.resolve_entry(resolve_config("ppo"), "EKFSLAM-v0", {})
    with pytest.raises(settings.SettingsError, match="give one of them"):
        train_run("EKFSLAM-v0", 0, entry, base.parent, resume=True, trained_agent=base)
    cloning = settings.validate_entry({**entry, "env_kwargs": {"max_episode_steps": 50}}, "EKFSLAM-v0", 0)
    with pytest.raises(settings.SettingsError, match="pretrain stage would clone a planner over it"):
        check_trained_agent(base, "EKFSLAM-v0", {**cloning, "pretrain": {"planner": "frontier"}})
    with pytest.raises(settings.SettingsError, match="no such model"):
        check_trained_agent(tmp_path / "nothing", "EKFSLAM-v0", cloning)
    assert check_trained_agent(base, "EKFSLAM-v0", cloning) == (
        base,
        base.with_name("model_vecnormalize.pkl"),
    )
    assert not out.exists()


def test_an_env_id_names_its_shipped_policy():
    from ekfslam_gym.cli.train import trained_agent_file
    from ekfslam_gym.pretrained import shipped_policy_file

    assert trained_agent_file("EKFSLAM-Maze-v1") == shipped_policy_file("EKFSLAM-Maze-v1")
    with pytest.raises(settings.SettingsError, match="neither a saved model"):
        trained_agent_file("EKFSLAM-Nowhere-v9")
