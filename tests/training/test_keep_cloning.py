"""Cloning kept up during PPO fine-tuning (``pretrain.keep_cloning``, ekfslam_gym.training.keep_cloning): its settings, that its
steps move the policy towards the demonstrated actions at the scheduled rate and reproducibly, and that train.py
runs them between PPO's updates, resumed runs included. Learning quality on the env is never asserted."""

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from ekfslam_gym.training import artefacts  # noqa: E402
from ekfslam_gym.training.cloning import behaviour_clone, fit_normalizer  # noqa: E402
from ekfslam_gym.training.settings import validate_pretrain  # noqa: E402
from tests.training.test_imitation import LabelEnv, synthetic  # noqa: E402


def test_keep_cloning_settings_validate():
    assert validate_pretrain({})["keep_cloning"] is None
    assert validate_pretrain({"keep_cloning": False})["keep_cloning"] is None
    assert validate_pretrain({"keep_cloning": True})["keep_cloning"] == {
        "batches": 8, "learning_rate": 3.0e-5, "decay": 1.0,
    }  # fmt: skip
    assert validate_pretrain({"keep_cloning": {"batches": 2, "decay": 0.9}})["keep_cloning"]["decay"] == 0.9
    for bad, match in (({"batch": 2}, "unknown pretrain.keep_cloning keys"), ({"batches": 0}, "batches"),
                       ({"batches": 2.0}, "batches"), ({"learning_rate": 0}, "learning_rate"),
                       ({"decay": 0}, "decay"), ({"decay": 1.5}, "decay"), ("often", "mapping")):  # fmt: skip
        with pytest.raises(ValueError, match=match):
            validate_pretrain({"keep_cloning": bad})


def _model(seed=0):
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import configure
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    torch.set_num_threads(1)
    venv = VecNormalize(DummyVecEnv([LabelEnv]), gamma=0.9)
    model = PPO("MlpPolicy", venv, seed=seed, n_steps=64, batch_size=64)
    model.set_logger(configure(None, []))
    return model


def _callback(model, demos, **settings):
    from ekfslam_gym.training.keep_cloning import KeepCloning

    callback = KeepCloning(demos, {"batches": 8, "learning_rate": 3.0e-3, "decay": 1.0, **settings},
                           batch_size=128, seed=0)  # fmt: skip
    callback.init_callback(model)
    return callback


def _parameters(model):
    return np.concatenate([p.detach().cpu().numpy().ravel() for p in model.policy.parameters()])


def test_cloning_steps_learn_the_demonstrated_labelling_at_the_scheduled_rate():
    """On a labelling a policy can learn (tests.training.test_imitation.synthetic), ten rollouts' cloning steps take an
    untrained policy from chance to the labels; the rate follows learning_rate * decay**rollout."""
    demos = synthetic()
    model = _model()
    fit_normalizer(model.get_vec_normalize_env(), demos)
    callback = _callback(model, demos, decay=0.8)
    assert behaviour_clone(model, demos, epochs=0).holdout_accuracy < 0.6  # about chance
    losses = []
    for rollout in range(10):
        model.num_timesteps = 64 * (rollout + 1)  # the end of rollout `rollout`
        assert callback.rollout_index() == rollout
        losses.append(callback.clone_steps())
        assert callback.optimizer.param_groups[0]["lr"] == pytest.approx(3.0e-3 * 0.8**rollout)
    assert losses[-1] < 0.5 * losses[0]  # ~0.2 against ~1.0 when this was written
    assert behaviour_clone(model, demos, epochs=0).holdout_accuracy > 0.85  # ~0.97 when this was written


def test_cloning_steps_are_reproducible_and_drawn_per_rollout():
    """Two models from the same seed take identical steps at the same rollout (so a resumed run repeats the
    uninterrupted one's), and the minibatches differ from one rollout to the next."""
    demos = synthetic()
    first, second = _model(), _model()
    for model in (first, second):
        fit_normalizer(model.get_vec_normalize_env(), demos)
        model.num_timesteps = 64 * 3
        _callback(model, demos).clone_steps()
    assert np.array_equal(_parameters(first), _parameters(second))
    callback = _callback(first, demos)
    drawn = [next(callback.batcher.minibatches(np.arange(len(demos)), 128, np.random.default_rng([0, k])))[0]
             for k in (0, 1)]  # fmt: skip
    assert not np.array_equal(drawn[0], drawn[1])


def test_train_py_keeps_cloning_between_ppo_updates_and_on_resume(tmp_path):
    """With PPO's learning rate 0, PPO cannot move the clone: a run without ``keep_cloning`` ends on the clone's
    weights, one with it does not, and its resumed run, which never clones again, still keeps cloning from the
    demonstrations it saved."""
    from ekfslam_gym.agents.ppo import PPOAgent

    import train

    def run(out, pretrain):
        train.main(["--config", "configs/ppo_primitives_bc.yaml", "--timesteps", "64", "--out", str(out),
                    "--seed", "0", "--no-progress", "--hyperparams", "n_steps=32", "batch_size=32", "n_epochs=1",
                    "n_envs=1", "eval_freq=0", "checkpoint_freq=32", "learning_rate=0.0", f"pretrain={pretrain}",
                    "env_kwargs={action: {kind: primitives, hold: 10}, max_episode_steps: 8}"])  # fmt: skip
        return tuple(_parameters(PPOAgent(out / name).model) for name in ("bc_model.zip", "model.zip"))

    clone, final = run(tmp_path / "plain", "{episodes: 2, epochs: 2}")
    assert np.array_equal(clone, final)
    kept = tmp_path / "kept"
    clone, final = run(kept, "{episodes: 2, epochs: 2, keep_cloning: {batches: 2, learning_rate: 1.0e-3}}")
    assert not np.allclose(clone, final)
    recorded = artefacts.read_run(kept)[2]["pretrain"]["keep_cloning"]
    assert recorded == {"batches": 2, "learning_rate": 1.0e-3, "decay": 1.0}

    (kept / "pretrain.json").unlink()
    train.main(["--resume", str(kept), "--timesteps", "128", "--no-progress"])
    assert not (kept / "pretrain.json").exists()  # not cloned again
    resumed = _parameters(PPOAgent(kept / "model.zip").model)
    assert not np.allclose(final, resumed)  # PPO's rate is 0: only the kept cloning moved it
