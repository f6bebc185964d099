"""Planner-guided training: the greedy planner's demonstrations in the primitives interface and the frontier
planner's in the waypoint and primitives interfaces, behaviour cloning into an SB3 policy (Discrete and Box
actions), and the ``pretrain`` switch of train.py's config. Never asserts learning quality on the env: cloning is checked on
synthetic tasks whose answers are known."""

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from ekfslam_gym.agents.planners import GreedyPrimitivesPlanner  # noqa: E402

from ekfslam_gym.envs.actions import PRIMITIVES  # noqa: E402
from ekfslam_gym.envs.rewards import REWARD_NAMES  # noqa: E402
from ekfslam_gym.training import artefacts, settings  # noqa: E402
from ekfslam_gym.training import demonstrations as demo_mod  # noqa: E402
from ekfslam_gym.training.cloning import (  # noqa: E402
    BOX_MATCH,
    behaviour_clone,
    discounted_running_returns,
    fit_normalizer,
    returns_to_go,
)
from ekfslam_gym.training.demonstrations import Demonstrations, collect  # noqa: E402
from ekfslam_gym.training.settings import validate_pretrain  # noqa: E402

PRIMITIVE_KWARGS = {"action": {"kind": "primitives", "hold": 10}, "max_episode_steps": 6}
WAYPOINT_KWARGS = {"action": {"kind": "waypoint", "hold": 10}, "max_episode_steps": 6}


def test_demonstrations_have_the_env_shapes_and_valid_planner_actions(tmp_path):
    demos = collect("EKFSLAM-v0", [30000, 30001], PRIMITIVE_KWARGS)
    env = gym.make("ekfslam_gym:EKFSLAM-v0", **PRIMITIVE_KWARGS)
    space = env.observation_space
    env.close()
    assert len(demos) == 12  # two episodes of six decisions
    assert demos.observations.shape == (12, *space.shape) and demos.observations.dtype == space.dtype
    assert all(space.contains(o) for o in demos.observations)  # raw observations, not normalised
    assert demos.actions.dtype == np.int64 and np.all(
        (0 <= demos.actions) & (demos.actions < len(PRIMITIVES))
    )
    assert demos.rewards.dtype == np.float64 and np.all(np.isfinite(demos.rewards))
    assert list(demos.episodes) == [0] * 6 + [1] * 6 and list(demos.seeds) == [30000, 30001]
    loaded = demo_mod.load(demo_mod.save(demos, tmp_path / "d.npz"))
    for name in ("observations", "actions", "rewards", "episodes", "seeds"):
        assert np.array_equal(getattr(loaded, name), getattr(demos, name)), name
    weights = loaded.meta.pop("reward_weights")
    assert loaded.meta == {
        "env_id": "EKFSLAM-v0",
        "env_kwargs": PRIMITIVE_KWARGS,
        "planner": "greedy",
        "planner_kwargs": {},
        "driver": None,
        "reward_terms": "unweighted",
    }
    # Every term is kept, unweighted, and weighted they sum to the reward.
    assert set(loaded.reward_terms) == set(REWARD_NAMES)
    for name, values in loaded.reward_terms.items():
        assert np.array_equal(values, demos.reward_terms[name]), name
    weighted = sum(w * loaded.reward_terms[name] for name, w in weights.items())
    np.testing.assert_allclose(weighted, loaded.rewards, rtol=1e-12, atol=1e-12)
    # Deterministic: the same seeds give the same demonstrations.
    again = collect("EKFSLAM-v0", [30000, 30001], PRIMITIVE_KWARGS)
    assert np.array_equal(again.actions, demos.actions) and np.array_equal(
        again.observations, demos.observations
    )


def test_reweighted_demonstrations_are_those_collected_under_the_other_reward():
    recorded = {**PRIMITIVE_KWARGS, "reward": {"collision": 5.0, "pose_variance": 8.0}}
    other = {**PRIMITIVE_KWARGS, "reward": {"info_gain": 0.5, "collision": 0.0, "pose_variance": 2.0}}
    demos = collect("EKFSLAM-v0", [30000, 30001], recorded)
    fresh = collect("EKFSLAM-v0", [30000, 30001], other)
    assert not np.allclose(demos.rewards, fresh.rewards)  # the rewards differ, the trajectories do not
    assert np.array_equal(demos.observations, fresh.observations) and np.array_equal(
        demos.actions, fresh.actions
    )
    again = demo_mod.reweighted(demos, demo_mod.env_reward_weights("EKFSLAM-v0", other))
    np.testing.assert_allclose(again.rewards, fresh.rewards, rtol=1e-9, atol=1e-12)
    assert set(again.reward_terms) == set(fresh.reward_terms) == set(REWARD_NAMES)
    assert again.meta["reward_weights"] == fresh.meta["reward_weights"]
    # The same weights give the same object.
    assert demo_mod.reweighted(demos, demos.meta["reward_weights"]) is demos
    # An older file kept the weighted terms with a non-zero weight only: it re-weighs those, and refuses others.
    weights = demos.meta["reward_weights"]
    kept = {name: w * demos.reward_terms[name] for name, w in weights.items() if w}
    meta = {k: v for k, v in demos.meta.items() if k != "reward_terms"}
    older = Demonstrations(
        demos.observations, demos.actions, demos.rewards, demos.episodes, demos.seeds, meta, kept
    )
    from_older = demo_mod.reweighted(older, demo_mod.env_reward_weights("EKFSLAM-v0", other))
    np.testing.assert_allclose(from_older.rewards, fresh.rewards, rtol=1e-9, atol=1e-12)
    needs = demo_mod.env_reward_weights("EKFSLAM-v0", {"reward": {"coverage": 10.0}})
    with pytest.raises(ValueError, match="coverage"):
        demo_mod.reweighted(older, needs)
    old = Demonstrations(demos.observations, demos.actions, demos.rewards, demos.episodes, demos.seeds,
                         {k: v for k, v in demos.meta.items() if k != "reward_weights"})  # fmt: skip
    with pytest.raises(ValueError, match="predate"):
        demo_mod.reweighted(old, fresh.meta["reward_weights"])


def test_planner_choices_are_the_greedy_agents_plan_from_the_belief():
    env = gym.make("ekfslam_gym:EKFSLAM-v0", **PRIMITIVE_KWARGS)
    planner = GreedyPrimitivesPlanner()
    observation, _ = env.reset(seed=30002)
    planner.reset(env, seed=30002)
    action = planner.act(observation)
    scores = planner.last_scores
    assert isinstance(action, np.int64) and np.isfinite(scores).any()
    assert action == int(np.argmax(scores))  # the best-scoring primitive, as the velocity agent picks
    env.close()
    velocity = gym.make("ekfslam_gym:EKFSLAM-v0")
    velocity.reset(seed=0)
    with pytest.raises(ValueError, match="primitives"):
        GreedyPrimitivesPlanner().reset(velocity, seed=0)
    velocity.close()


class TurnInPlace:
    """A driver that only turns in place (primitive 7): the robot stays where it started."""

    name = "turn"

    def reset(self, env, seed=None):
        pass

    def act(self, observation):
        return np.int64(PRIMITIVES.index((0.0, 1.0)))


def test_dagger_collection_executes_the_driver_and_records_the_planners_labels():
    demos = collect("EKFSLAM-v0", [30003], PRIMITIVE_KWARGS, driver=TurnInPlace())
    planner = collect("EKFSLAM-v0", [30003], PRIMITIVE_KWARGS)
    assert demos.meta["driver"] == "turn" and len(demos) == 6
    position = demos.observations[:, :2]  # the estimated position: the driver never moved the robot
    assert np.ptp(position, axis=0).max() < 0.02 < np.ptp(planner.observations[:, :2], axis=0).max()
    assert demos.actions[0] == planner.actions[0]  # the same first state, the same label
    assert np.any(demos.actions != PRIMITIVES.index((0.0, 1.0)))  # labels are the planner's, not the driver's


def test_frontier_demonstrations_are_waypoint_goals_and_a_driver_can_drive():
    demos = collect("EKFSLAM-v0", [30000], WAYPOINT_KWARGS, planner="frontier")
    assert demos.meta["planner"] == "frontier" and len(demos) == 6
    assert demos.actions.dtype == np.float32 and demos.actions.shape == (6, 2)
    assert np.all(np.abs(demos.actions) <= 1.0) and np.ptp(demos.actions, axis=0).max() > 0
    # DAgger in the waypoint interface: the driver's goals (straight back here) are executed, the labels are the
    # planner's (a goal ahead on its path, never straight back).
    backwards = type("Back", (), {"name": "back", "reset": lambda self, env, seed=None: None,
                                  "act": lambda self, obs: np.array([-1.0, 0.0], dtype=np.float32)})()  # fmt: skip
    driven = collect("EKFSLAM-v0", [30000], WAYPOINT_KWARGS, planner="frontier", driver=backwards)
    assert np.array_equal(driven.actions[0], demos.actions[0])  # the same first state, the same label
    assert not np.array_equal(driven.observations[1:], demos.observations[1:])  # the driver drove
    assert not np.any(np.all(np.isclose(driven.actions, [-1.0, 0.0]), axis=1))
    with pytest.raises(ValueError, match="waypoint or primitives, not 'velocity'"):
        collect("EKFSLAM-v0", [30000], {"max_episode_steps": 6}, planner="frontier")
    with pytest.raises(ValueError, match="primitives, not 'waypoint'"):
        collect("EKFSLAM-v0", [30000], WAYPOINT_KWARGS, planner="greedy")


def test_frontier_demonstrations_in_a_primitives_env_are_primitive_indices():
    """The frontier planner in a primitives env (configs/ppo_frontier_primitives_bc.yaml's teacher) labels with
    the index of a primitive, as the greedy one does, so the Discrete policy clones it the same way."""
    demos = collect("EKFSLAM-v0", [30000], PRIMITIVE_KWARGS, planner="frontier")
    assert demos.meta["planner"] == "frontier" and len(demos) == 6
    assert demos.actions.dtype == np.int64 and demos.actions.shape == (6,)
    assert np.all((demos.actions >= 0) & (demos.actions < len(PRIMITIVES)))


def test_planner_kwargs_reach_the_demonstrator_and_are_recorded(monkeypatch):
    """``pretrain.planner_kwargs`` (e.g. the frontier planner's active loop closing) builds the demonstrator, for
    the first demonstrations and for DAgger's labels alike, and the demonstrations record them."""
    built = []
    original = demo_mod.make_planner

    def spy(name, kind, **kwargs):
        planner = original(name, kind, **kwargs)
        built.append(planner)
        return planner

    monkeypatch.setattr(demo_mod, "make_planner", spy)
    kwargs = {"relocalize_std": 0.25, "goal_distance": 1.25}
    demos = collect("EKFSLAM-v0", [30000], PRIMITIVE_KWARGS, planner="frontier", planner_kwargs=kwargs)
    driven = collect("EKFSLAM-v0", [30001], PRIMITIVE_KWARGS, planner="frontier", planner_kwargs=kwargs,
                     driver=TurnInPlace())  # fmt: skip
    assert [(p.relocalize_std, p.goal_distance) for p in built] == [(0.25, 1.25)] * 2
    assert demos.meta["planner_kwargs"] == kwargs == driven.meta["planner_kwargs"]
    assert collect("EKFSLAM-v0", [30000], PRIMITIVE_KWARGS).meta["planner_kwargs"] == {}


def test_reweighting_is_the_envs_own_weighted_sum_of_each_pairs_terms():
    """Pair by pair, the re-weighted reward is exactly ``rewards.weigh`` of the pair's terms, the sum the env
    takes; a weight of 0 drops its term whatever it holds."""
    from ekfslam_gym.envs.config import RewardConfig
    from ekfslam_gym.envs.rewards import nonzero_weights, weigh

    rng = np.random.default_rng(5)
    terms = {name: rng.normal(size=6) for name in REWARD_NAMES}
    terms["step_cost"] = np.full(6, -1.0)
    recorded = {name: 1.0 for name in REWARD_NAMES}
    demos = Demonstrations(np.zeros((6, 1)), np.zeros(6, dtype=np.int64), np.zeros(6), np.zeros(6, dtype=np.int64),
                           np.array([30000]), {"reward_weights": recorded, "reward_terms": "unweighted"}, terms)  # fmt: skip
    weights = {"info_gain": 0.5, "collision": 3.0, "step_cost": 0.0, "coverage": 0.25, "pose_variance": 8.0}
    again = demo_mod.reweighted(demos, weights)
    pairs = nonzero_weights(RewardConfig(**weights))
    assert [name for name, _ in pairs] == ["info_gain", "collision", "coverage", "pose_variance"]
    expected = [weigh({name: float(v[i]) for name, v in terms.items()}, pairs) for i in range(6)]
    assert again.rewards.tolist() == expected  # bit for bit
    with pytest.raises(ValueError, match="reward.collision"):
        demo_mod.reweighted(demos, {**weights, "collision": float("nan")})


def test_discounted_returns_known_answers():
    demos = Demonstrations(np.zeros((5, 1)), np.zeros(5, dtype=np.int64), np.array([1.0, 2.0, 3.0, 4.0, 5.0]),
                           np.array([0, 0, 0, 1, 1]), np.array([0, 1]))  # fmt: skip
    # VecNormalize's running return, restarted at each episode: 1, 0.5 + 2, 1.25 + 3 | 4, 2 + 5.
    assert np.allclose(discounted_running_returns(demos, 0.5), [1.0, 2.5, 4.25, 4.0, 7.0])
    # Returns to go: 1 + 0.5 * 2 + 0.25 * 3, 2 + 1.5, 3 | 4 + 2.5, 5.
    assert np.allclose(returns_to_go(demos.rewards, demos.episodes, 0.5), [2.75, 3.5, 3.0, 6.5, 5.0])


class LabelEnv(gym.Env):
    """A 4-d Box observation and Discrete(3) actions: the spaces a cloned policy needs, nothing more."""

    observation_space = gym.spaces.Box(-np.inf, np.inf, (4,), np.float32)
    action_space = gym.spaces.Discrete(3)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(4, dtype=np.float32), {}

    def step(self, action):
        return np.zeros(4, dtype=np.float32), 0.0, True, False, {}


def synthetic(n_episodes=20, length=100, seed=0):
    """Observations N(3, 2^2) per component, action = argmax of a fixed linear map of the centred observation:
    a deterministic function of the observation, so a policy can clone it almost perfectly."""
    rng = np.random.default_rng(seed)
    n = n_episodes * length
    obs = (3.0 + 2.0 * rng.standard_normal((n, 4))).astype(np.float32)
    weights = np.array([[1.0, -1.0, 0.5, 0.0], [-0.5, 1.0, 1.0, -1.0], [0.0, 0.3, -1.0, 1.0]])
    actions = np.argmax((obs - 3.0) @ weights.T, axis=1).astype(np.int64)
    return Demonstrations(obs, actions, rng.standard_normal(n), np.repeat(np.arange(n_episodes), length),
                          np.arange(n_episodes))  # fmt: skip


def test_behaviour_cloning_learns_a_deterministic_labelling():
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    torch.set_num_threads(1)
    demos = synthetic()
    venv = VecNormalize(DummyVecEnv([LabelEnv]), gamma=0.9)
    model = PPO("MlpPolicy", venv, seed=0, n_steps=64, batch_size=64, gamma=0.9)
    fit_normalizer(venv, demos)
    assert np.allclose(venv.obs_rms.mean, demos.observations.mean(axis=0), atol=1e-5)
    assert np.allclose(venv.obs_rms.var, demos.observations.var(axis=0), rtol=1e-4)
    assert venv.obs_rms.count == len(demos)
    assert np.isclose(venv.ret_rms.var, np.var(discounted_running_returns(demos, 0.9)))
    before = behaviour_clone(model, demos, epochs=0, seed=0)
    report = behaviour_clone(model, demos, epochs=15, batch_size=128, learning_rate=3e-3, seed=0)
    assert report.holdout_episodes == 2 and report.holdout_pairs == 200 and report.train_pairs == 1800
    assert before.holdout_accuracy < 0.6  # an untrained policy: about chance
    assert report.train_accuracy > 0.9 and report.holdout_accuracy > 0.9  # ~0.97-0.99 when this was written
    assert np.isfinite(report.value_loss) and report.action_loss < 0.3


class GoalEnv(LabelEnv):
    """LabelEnv with a waypoint-like Box(-1, 1, (2,)) action."""

    action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)


def test_behaviour_cloning_learns_a_continuous_labelling():
    """Box actions (the waypoint interface): the Gaussian policy's mean is cloned onto goals that are a smooth
    function of the observation; its spread shrinks from the initial std of 1."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    torch.set_num_threads(1)
    discrete = synthetic()
    weights = np.array([[0.4, -0.3, 0.2, 0.0], [-0.2, 0.3, 0.3, -0.3]])
    goals = np.tanh((discrete.observations - 3.0) @ weights.T).astype(np.float32)
    demos = Demonstrations(discrete.observations, goals, discrete.rewards, discrete.episodes, discrete.seeds)
    venv = VecNormalize(DummyVecEnv([GoalEnv]), gamma=0.9)
    model = PPO("MlpPolicy", venv, seed=0, n_steps=64, batch_size=64, gamma=0.9)
    fit_normalizer(venv, demos)
    before = behaviour_clone(model, demos, epochs=0, seed=0)
    report = behaviour_clone(model, demos, epochs=15, batch_size=128, learning_rate=3e-3, seed=0)
    assert before.holdout_accuracy < 0.3  # an untrained mean near 0: few goals within BOX_MATCH of it
    assert report.train_accuracy > 0.9 and report.holdout_accuracy > 0.9
    assert float(model.policy.log_std.detach().exp().max()) < 0.5 and BOX_MATCH == 0.1
    with pytest.raises(ValueError, match="do not fit"):
        behaviour_clone(model, discrete, epochs=1)  # (N,) primitive indices for a Box(2) policy


def noisy_labels(n_episodes=12, length=40, flip=0.4, seed=0):
    """``synthetic``'s labelling with ``flip`` of the labels drawn at random: a small, noisy training set on which
    a policy cloned long at a high rate chases the noise, so its held-back accuracy rises and then falls."""
    clean = synthetic(n_episodes, length, seed)
    rng = np.random.default_rng(seed + 1)
    actions = np.where(rng.random(len(clean)) < flip, rng.integers(3, size=len(clean)), clean.actions)
    return Demonstrations(clean.observations, actions, clean.rewards, clean.episodes, clean.seeds)


def test_the_rewards_reach_the_cloned_actions_only_through_the_value_heads_share_of_the_gradient_clip():
    """The same demonstrations under two reward settings: without the value head the clones' actors are
    identical; with it they differ, because the action and value losses share one gradient-norm clip
    (``max_grad_norm`` over every parameter, as SB3's PPO does), so the value loss's size scales the actor's
    steps. Why two Large runs reading one file under different rewards start from different clones."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    torch.set_num_threads(1)

    def actor_after_cloning(reward_scale, value):
        torch.manual_seed(0)
        model = PPO("MlpPolicy", DummyVecEnv([LabelEnv]), seed=0, n_steps=64, batch_size=64, gamma=0.9)
        demos = synthetic()
        demos.rewards = demos.rewards * reward_scale
        behaviour_clone(model, demos, epochs=3, batch_size=128, learning_rate=3e-3, seed=0, value=value)
        actor = ("action_net", "mlp_extractor.policy_net")
        params = [p.detach().flatten() for n, p in model.policy.named_parameters() if n.startswith(actor)]
        return torch.cat(params)

    assert torch.equal(actor_after_cloning(1.0, False), actor_after_cloning(10.0, False))
    assert not torch.equal(actor_after_cloning(1.0, True), actor_after_cloning(10.0, True))


def test_best_epoch_keeps_the_weights_of_the_epoch_that_best_predicts_the_held_back_episodes():
    """Early stopping: the held-back accuracy is measured before and after every epoch; with ``best_epoch`` the
    policy ends with the weights of the first epoch of highest accuracy, which are exactly those cloning for that
    many epochs gives (measuring draws nothing at random), and the report is theirs. Without it, the same curve is
    reported and the last epoch's weights are kept."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    torch.set_num_threads(1)
    demos = noisy_labels()

    def clone(epochs, best_epoch):
        model = PPO("MlpPolicy", DummyVecEnv([LabelEnv]), seed=0, n_steps=64, batch_size=64,
                    policy_kwargs={"net_arch": [256, 256]})  # fmt: skip
        report = behaviour_clone(model, demos, epochs=epochs, batch_size=32, learning_rate=1e-2, holdout=0.25,
                                 seed=0, best_epoch=best_epoch)  # fmt: skip
        return model, report

    last_model, last = clone(30, False)
    best_model, best = clone(30, True)
    assert len(best.holdout_by_epoch) == 31 and best.holdout_by_epoch == last.holdout_by_epoch
    assert last.kept_epoch == 30 and last.holdout_accuracy == last.holdout_by_epoch[-1]
    kept = int(np.argmax(best.holdout_by_epoch))
    # The curve peaks inside: at epoch 9 of 30 when this was written, 0.64 against the last epoch's 0.56.
    assert 0 < kept < 30 and best.kept_epoch == kept
    assert best.holdout_accuracy == max(best.holdout_by_epoch) > last.holdout_accuracy
    early_model, early = clone(kept, False)
    weights, early_weights = best_model.policy.state_dict(), early_model.policy.state_dict()
    assert all(torch.equal(weights[name], early_weights[name]) for name in weights)
    assert (early.train_accuracy, early.holdout_accuracy) == (best.train_accuracy, best.holdout_accuracy)
    assert (early.action_loss, early.value_loss) == (best.action_loss, best.value_loss)
    assert not all(torch.equal(weights[name], last_model.policy.state_dict()[name]) for name in weights)
    with pytest.raises(ValueError, match="none are held back"):
        behaviour_clone(last_model, demos, epochs=1, holdout=0.0, best_epoch=True)


def test_best_epoch_keeps_the_earliest_of_tied_epochs():
    """Ties go to the earliest epoch, so early stopping never trains longer than it has to: at learning rate 0
    no epoch moves the weights, the held-back curve is flat, and the epoch kept is 0, the weights cloning began
    with, whose report it gives."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    torch.set_num_threads(1)
    model = PPO("MlpPolicy", DummyVecEnv([LabelEnv]), seed=0, n_steps=64, batch_size=64)
    start = {name: tensor.clone() for name, tensor in model.policy.state_dict().items()}
    report = behaviour_clone(model, noisy_labels(), epochs=4, batch_size=32, learning_rate=0.0, holdout=0.25,
                             seed=0, best_epoch=True)  # fmt: skip
    assert len(report.holdout_by_epoch) == 5 and len(set(report.holdout_by_epoch)) == 1
    assert report.kept_epoch == 0 and report.holdout_accuracy == report.holdout_by_epoch[0]
    assert np.isnan(report.action_loss)  # epoch 0 trained nothing, so it has no loss to report
    weights = model.policy.state_dict()
    assert all(torch.equal(weights[name], start[name]) for name in start)


def cue_task(n_episodes=120, seed=0):
    """Episodes of 8-24 steps whose every action is a cue shown only at the first step (one-hot in the first
    three components; zeros afterwards, with the fourth component counting time): only a policy that remembers
    the episode's start can clone it, a feed-forward one is right about a third of the time after the start."""
    rng = np.random.default_rng(seed)
    obs, actions, episodes = [], [], []
    for k in range(n_episodes):
        length, cue = int(rng.integers(8, 25)), int(rng.integers(3))
        steps = np.zeros((length, 4), dtype=np.float32)
        steps[0, cue] = 1.0
        steps[:, 3] = np.arange(length) / 24.0
        obs.append(steps)
        actions.append(np.full(length, cue, dtype=np.int64))
        episodes.append(np.full(length, k, dtype=np.int64))
    obs, actions, episodes = np.concatenate(obs), np.concatenate(actions), np.concatenate(episodes)
    return Demonstrations(obs, actions, rng.standard_normal(len(obs)), episodes, np.arange(n_episodes))


def test_a_recurrent_policy_is_cloned_on_whole_episodes_and_remembers_their_start():
    """RecurrentPPO's LSTM reads each episode from its first step (episodes of unequal length, padded and masked
    in a batch), so it learns a labelling that only memory can give; the same cloning of a feed-forward policy
    stays near chance, which shows the task needs the memory."""
    import torch
    from sb3_contrib import RecurrentPPO
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    torch.set_num_threads(1)
    demos = cue_task()
    recurrent = RecurrentPPO("MlpLstmPolicy", DummyVecEnv([LabelEnv]), seed=0, n_steps=32, batch_size=32,
                             policy_kwargs={"lstm_hidden_size": 32, "net_arch": [32]})  # fmt: skip
    flat = PPO("MlpPolicy", DummyVecEnv([LabelEnv]), seed=0, n_steps=32, batch_size=32)
    reports = {}
    for name, model in (("recurrent", recurrent), ("flat", flat)):
        reports[name] = behaviour_clone(model, demos, epochs=30, batch_size=128, learning_rate=3e-3, seed=0)
    rec, ff = reports["recurrent"], reports["flat"]
    assert rec.holdout_episodes == 12 and rec.train_pairs + rec.holdout_pairs == len(demos)
    assert (rec.train_pairs, rec.holdout_pairs) == (ff.train_pairs, ff.holdout_pairs)  # the same split
    assert rec.train_accuracy > 0.9 and rec.holdout_accuracy > 0.9  # 1.0 when this was written
    assert ff.holdout_accuracy < 0.6  # ~0.4 when this was written: a third, plus the first steps
    assert np.isfinite(rec.value_loss) and rec.action_loss < 0.3


def test_pretrain_setting_validates():
    assert validate_pretrain(None) is None and validate_pretrain(False) is None
    settings = validate_pretrain({"episodes": 5})
    assert settings["episodes"] == 5 and settings["planner"] == "greedy" and settings["seed"] == 30000
    for bad, match in (({"episode": 5}, "unknown pretrain keys"), ({"planner": "lawnmower"}, "planner"),
                       ({"epochs": 0}, "epochs"), ({"episodes": 2.5}, "episodes"), ({"holdout": 1.0}, "holdout"),
                       ({"learning_rate": -1}, "learning_rate"), ({"value": "yes"}, "value"),
                       ({"best_epoch": 1}, "best_epoch"), ({"best_epoch": True, "holdout": 0.0}, "holdout > 0"),
                       ({"seed": 9990, "episodes": 20}, "held-out"), ("greedy", "mapping"),
                       ({"seed": 9900, "episodes": 50, "dagger_rounds": 1, "dagger_episodes": 60}, "held-out"),
                       ({"dagger_rounds": -1}, "dagger_rounds")):  # fmt: skip
        with pytest.raises(ValueError, match=match):
            validate_pretrain(bad)
    with pytest.raises(ValueError, match="evaluation"):
        validate_pretrain({"seed": 500, "episodes": 10}, {"eval_seed": 505, "eval_episodes": 10})
    assert (
        validate_pretrain({"planner": "frontier"}, {"env_kwargs": WAYPOINT_KWARGS})["planner"] == "frontier"
    )
    assert (
        validate_pretrain({"planner": "frontier"}, {"env_kwargs": PRIMITIVE_KWARGS})["planner"] == "frontier"
    )
    for planner, kwargs in (("frontier", {}), ("greedy", WAYPOINT_KWARGS), ("greedy", {})):
        with pytest.raises(ValueError, match="demonstrates in action.kind"):
            validate_pretrain({"planner": planner}, {"env_kwargs": kwargs})
    relocalizing = {"planner": "frontier", "planner_kwargs": {"relocalize_std": 0.2}}
    assert validate_pretrain(relocalizing, {"env_kwargs": PRIMITIVE_KWARGS})["planner_kwargs"] == {
        "relocalize_std": 0.2
    }
    for bad, match in (({"relocalize_std": -1.0}, "relocalize_std"), ({"no_such": 1}, "no_such"),
                       ([0.2], "mapping"), ({"clearance": 0.1}, "clearance")):  # fmt: skip
        with pytest.raises(ValueError, match=f"planner_kwargs.*{match}|{match}.*planner_kwargs"):
            validate_pretrain({"planner": "frontier", "planner_kwargs": bad}, {"env_kwargs": WAYPOINT_KWARGS})


def test_train_settings_switch_is_checked_and_absent_means_none(tmp_path):

    assert settings.load_entry(Path("configs/ppo_primitives.yaml"), "EKFSLAM-v0")["pretrain"] is None
    for env_id in ("EKFSLAM-v0", "EKFSLAM-Loop-v0"):
        entry = settings.load_entry(Path("configs/ppo_primitives_bc.yaml"), env_id)
        assert (
            entry["pretrain"]["planner"] == "greedy" and entry["env_kwargs"]["action"]["kind"] == "primitives"
        )
    bad = tmp_path / "bad.yaml"
    bad.write_text("EKFSLAM-v0: {n_steps: 64}\ntrain_settings: {EKFSLAM-v0: {pretrain: {epoch: 3}}}\n")
    with pytest.raises(settings.SettingsError, match="unknown pretrain keys"):
        settings.load_entry(bad, "EKFSLAM-v0")
    bad.write_text("EKFSLAM-v0: {n_steps: 64, pretrain: {epochs: 3}}\n")
    with pytest.raises(settings.SettingsError, match="train_settings"):
        settings.load_entry(bad, "EKFSLAM-v0")


def test_bc_warm_start_trains_end_to_end_and_is_skipped_on_resume(tmp_path, capsys):
    import train

    out = tmp_path / "run"
    args = ["--config", "configs/ppo_primitives_bc.yaml", "--timesteps", "64", "--out", str(out), "--seed", "0",
            "--no-progress", "--hyperparams", "n_steps=32", "batch_size=32", "n_epochs=1", "n_envs=1",
            "eval_freq=0", "checkpoint_freq=0", "pretrain={episodes: 2, epochs: 2}",
            "env_kwargs={action: {kind: primitives, hold: 10}, max_episode_steps: 8}"]  # fmt: skip
    train.main(args)
    for name in ("model.zip", "model_vecnormalize.pkl", "bc_model.zip", "bc_model_vecnormalize.pkl",
                 "demonstrations.npz", "pretrain.json"):  # fmt: skip
        assert (out / name).is_file(), name
    record = json.loads((out / "pretrain.json").read_text())
    assert record["pairs"] == 16 and record["clone"]["holdout_episodes"] == 1
    saved = artefacts.read_run(out)[2]["pretrain"]
    assert saved["episodes"] == 2 and saved["epochs"] == 2 and saved["seed"] == 30000  # defaults recorded too
    demos = demo_mod.load(out / "demonstrations.npz")
    assert demos.meta["env_kwargs"]["max_episode_steps"] == 8

    (out / "pretrain.json").unlink()
    train.main(["--resume", str(out), "--timesteps", "96", "--no-progress"])
    assert not (out / "pretrain.json").exists()  # resuming continues PPO, it does not clone again

    # Reusing saved demonstrations (they must be of the run's env settings), and one DAgger round.
    path = out / "demonstrations.npz"
    reuse = [*args[:5], str(tmp_path / "reuse"), *args[6:-2],
             f"pretrain={{path: {path}, epochs: 2, dagger_rounds: 1, dagger_episodes: 1}}", args[-1]]  # fmt: skip
    train.main(reuse)
    record = json.loads((tmp_path / "reuse" / "pretrain.json").read_text())
    assert record["pairs"] == 24 and record["episodes"] == 3 and len(record["rounds"]) == 2
    assert len(record["dagger_agreement"]) == 1 and 0 <= record["dagger_agreement"][0] <= 1
    assert not (tmp_path / "reuse" / "demonstrations.npz").exists()
    assert demo_mod.load(tmp_path / "reuse" / "dagger.npz").seeds.tolist() == [30000, 30001, 30200]
    mismatch = [*reuse[:-1], "env_kwargs={action: {kind: primitives, hold: 5}, max_episode_steps: 8}"]
    with pytest.raises(SystemExit) as exit_:  # a pretrain.path that does not fit the run: a usage error
        train.main(mismatch)
    assert exit_.value.code == 2 and "pretrain.path" in capsys.readouterr().err
    # Another reward reuses them, its rewards recomputed; one needing a term they lack is refused.
    kinds = "action: {kind: primitives, hold: 10}, max_episode_steps: 8"
    rewarded = [
        *reuse[:5],
        str(tmp_path / "rewarded"),
        *reuse[6:-1],
        f"env_kwargs={{{kinds}, reward: {{collision: 3.0}}}}",
    ]
    train.main(rewarded)
    dagger = demo_mod.load(tmp_path / "rewarded" / "dagger.npz")
    assert dagger.meta["reward_weights"]["collision"] == 3.0 and dagger.meta["reweighted_from"] == str(path)
    assert dagger.meta["env_kwargs"]["reward"] == {"collision": 3.0}
    # Every term is recorded unweighted, so any reward can re-weigh them, a term weighted 0 when collected too.
    assert set(dagger.reward_terms) == set(REWARD_NAMES) and dagger.meta["reward_terms"] == "unweighted"


def test_a_recurrent_config_clones_the_planner_with_a_dagger_round_at_smoke_size(tmp_path):
    """configs/ppo_lstm.yaml with a ``pretrain`` section: RecurrentPPO is cloned on the greedy planner's
    episodes, drives one DAgger round with its LSTM state, and is saved as a RecurrentPPO clone that evaluates;
    with ``best_epoch``, each cloning records its held-back curve in pretrain.json and keeps its best epoch."""
    from ekfslam_gym.agents.ppo import PPOAgent

    import train
    from ekfslam_gym.evaluation.rollout import evaluate_agent

    out = tmp_path / "lstm"
    train.main(["--config", "configs/ppo_lstm.yaml", "--timesteps", "64", "--out", str(out), "--seed", "0",
                "--no-progress", "--hyperparams", "n_steps=32", "batch_size=32", "n_epochs=1", "n_envs=1",
                "eval_freq=0", "checkpoint_freq=0",
                "pretrain={episodes: 2, epochs: 2, dagger_rounds: 1, dagger_episodes: 1, best_epoch: true}",
                "env_kwargs={action: {kind: primitives, hold: 10}, max_episode_steps: 8}"])  # fmt: skip
    record = json.loads((out / "pretrain.json").read_text())
    assert record["pairs"] == 24 and len(record["rounds"]) == 2 and len(record["dagger_agreement"]) == 1
    for clone_round in record["rounds"]:  # each keeps its best of two epochs, or 0: the weights it began with
        curve = clone_round["holdout_by_epoch"]
        assert len(curve) == 3 and clone_round["kept_epoch"] == int(np.argmax(curve))
        assert clone_round["holdout_accuracy"] == max(curve)
    assert record["clone"]["holdout_episodes"] == 1 and 0 <= record["clone"]["holdout_accuracy"] <= 1
    clone = PPOAgent(out / "bc_model.zip")
    assert type(clone.model).__name__ == "RecurrentPPO" and clone.recurrent
    kwargs = {"action": {"kind": "primitives", "hold": 10}, "max_episode_steps": 8}
    first, again = (evaluate_agent(clone, "EKFSLAM-v0", [20000], kwargs)[0] for _ in range(2))
    assert first["map_log_det"] == again["map_log_det"]  # deterministic, its LSTM state reset at each episode


def _smoke_train(config, out, pretrain, action_kind, env_id="EKFSLAM-v0"):
    """``config``'s ``env_id`` entry through train.py at smoke size: the demonstration episodes ``pretrain`` asks
    for, of 8 decisions (Dict observation with the belief image), cloned, then 64 steps of PPO, into ``out``."""
    import train

    train.main(["--config", config, "--env-id", env_id, "--timesteps", "64", "--out", str(out), "--seed", "0",
                "--no-progress", "--hyperparams", "n_steps=32", "batch_size=32", "n_epochs=1", "n_envs=1",
                "eval_freq=0", "checkpoint_freq=0", f"pretrain={pretrain}",
                f"env_kwargs={{action: {{kind: {action_kind}, hold: 10}}, max_episode_steps: 8, "
                "observation: {kind: dict, belief_image: true}}"])  # fmt: skip


def test_the_cnn_recipe_clones_into_the_belief_cnn_at_smoke_size(tmp_path):
    """configs/experiments/ppo_belief_cnn_bc.yaml (the shipped EKFSLAM-v0 recipe, less its coverage bonus, wider image and
    frontier teacher): demonstrations of Dict observations with the belief image are cloned into the
    MultiInputPolicy's BeliefCNN, then PPO starts from the clone."""
    from ekfslam_gym.agents import PPOAgent
    from ekfslam_gym.agents.extractors import BeliefCNN

    entry = settings.load_entry(Path("configs/experiments/ppo_belief_cnn_bc.yaml"), "EKFSLAM-v0")
    assert (
        entry["pretrain"]["episodes"] == 1000 and entry["env_kwargs"]["observation"]["belief_image"] is True
    )
    out = tmp_path / "run"
    _smoke_train("configs/experiments/ppo_belief_cnn_bc.yaml", out, "{episodes: 2, epochs: 2}", "primitives")
    demos = demo_mod.load(out / "demonstrations.npz")
    assert demos.meta["env_kwargs"]["observation"]["belief_image"] is True
    assert json.loads((out / "pretrain.json").read_text())["pairs"] == 16
    for name in ("bc_model.zip", "model.zip"):
        agent = PPOAgent(out / name)
        assert isinstance(agent.model.policy.features_extractor, BeliefCNN)


def test_the_shipped_recipe_clones_the_frontier_planners_primitives_at_smoke_size(tmp_path):
    """configs/ppo_frontier_primitives_bc.yaml (the shipped EKFSLAM-v0 recipe): the frontier planner's primitive
    indices, with Dict observations and the belief image, cloned into the Discrete MultiInputPolicy, then PPO
    starts from the clone."""
    from ekfslam_gym.agents import PPOAgent

    config = "configs/ppo_frontier_primitives_bc.yaml"
    entry = settings.load_entry(Path(config), "EKFSLAM-v0")
    assert (
        entry["pretrain"]["planner"] == "frontier" and entry["env_kwargs"]["action"]["kind"] == "primitives"
    )
    out = tmp_path / "run"
    _smoke_train(config, out, "{planner: frontier, episodes: 2, epochs: 2}", "primitives")
    demos = demo_mod.load(out / "demonstrations.npz")
    assert (
        demos.meta["planner"] == "frontier"
        and demos.actions.dtype == np.int64
        and demos.actions.shape == (16,)
    )
    record = json.loads((out / "pretrain.json").read_text())
    assert record["pairs"] == 16 and 0 <= record["clone"]["holdout_accuracy"] <= 1
    for name in ("bc_model.zip", "model.zip"):
        assert PPOAgent(out / name).model.action_space == gym.spaces.Discrete(len(PRIMITIVES))


def test_the_frontier_recipe_clones_waypoint_goals_at_smoke_size(tmp_path):
    """configs/experiments/ppo_frontier_bc.yaml: the frontier planner's waypoint goals, with Dict observations and the belief
    image, cloned into the Gaussian MultiInputPolicy, then PPO starts from the clone."""
    from ekfslam_gym.agents import PPOAgent

    entry = settings.load_entry(Path("configs/experiments/ppo_frontier_bc.yaml"), "EKFSLAM-v0")
    assert entry["pretrain"]["planner"] == "frontier" and entry["env_kwargs"]["action"]["kind"] == "waypoint"
    out = tmp_path / "run"
    _smoke_train(
        "configs/experiments/ppo_frontier_bc.yaml",
        out,
        "{planner: frontier, episodes: 2, epochs: 2}",
        "waypoint",
    )
    demos = demo_mod.load(out / "demonstrations.npz")
    assert demos.actions.dtype == np.float32 and demos.actions.shape == (16, 2)
    record = json.loads((out / "pretrain.json").read_text())
    assert record["pairs"] == 16 and 0 <= record["clone"]["holdout_accuracy"] <= 1
    for name in ("bc_model.zip", "model.zip"):
        assert PPOAgent(out / name).model.action_space == gym.spaces.Box(-1.0, 1.0, (2,), np.float32)


def test_the_shipped_recipe_is_the_cnn_recipe_with_the_coverage_bonus_a_wider_image_and_the_frontier_teacher():
    """configs/experiments/ppo_belief_cnn_bc_coverage.yaml differs from configs/experiments/ppo_belief_cnn_bc.yaml only in the reward,
    configs/experiments/ppo_belief_cnn_bc_coverage_wide.yaml from it only in the belief image's reach,
    configs/ppo_frontier_primitives_bc.yaml (models/ppo_EKFSLAM-v0.zip's recipe) from that only in the teacher
    and the discount, and the shipped model's record holds that same entry (less where its demonstrations were
    read: seeds 1-4 reused seed 0's)."""
    import yaml

    def entry(name):
        return settings.load_entry(_config_path(name), "EKFSLAM-v0")

    base, bonus, wide, frontier = (
        entry("ppo_belief_cnn_bc"),
        entry("ppo_belief_cnn_bc_coverage"),
        entry("ppo_belief_cnn_bc_coverage_wide"),
        entry("ppo_frontier_primitives_bc"),
    )
    record = yaml.safe_load(Path("models/ppo_EKFSLAM-v0_config.yaml").read_text())["entry"]
    assert record["pretrain"]["path"].endswith("demonstrations.npz") and frontier["pretrain"]["path"] is None
    record["pretrain"]["path"] = None
    record["pretrain"].setdefault("planner_kwargs", None)  # recorded before the key existed
    record["pretrain"].setdefault("keep_cloning", None)  # likewise
    record["pretrain"].setdefault("best_epoch", False)  # likewise
    assert record == frontier
    assert frontier["pretrain"]["planner"] == "frontier" and wide["pretrain"]["planner"] == "greedy"
    assert (frontier["gamma"], wide["gamma"]) == (0.995, 0.98)
    frontier["pretrain"]["planner"], frontier["gamma"] = "greedy", 0.98
    assert frontier == wide
    assert wide["env_kwargs"]["observation"]["belief_extent"] == 16.0
    wide["env_kwargs"]["observation"]["belief_extent"] = 8.0
    assert wide == bonus
    assert bonus["env_kwargs"].pop("reward") == {"coverage": 1.0}
    assert bonus == base


def _config_path(name):
    """configs/<name>.yaml, a shipped recipe or an example, else configs/experiments/<name>.yaml."""
    top = Path(f"configs/{name}.yaml")
    return top if top.is_file() else Path(f"configs/experiments/{name}.yaml")


def _large_entry(name):
    """configs/<name>.yaml's (or configs/experiments/<name>.yaml's) EKFSLAM-Large-v0 entry, as train.py reads it."""

    return settings.load_entry(_config_path(name), "EKFSLAM-Large-v0")


def test_the_large_mlp_recipes_differ_only_where_named():
    """configs/experiments/ppo_primitives_home_keep_bc.yaml (the recipe shipped before the recurrent one) differs from
    configs/experiments/ppo_primitives_relocalize03_bc.yaml (shipped before it) only in the teacher's settings and the cloning
    kept up during fine-tuning; that one from configs/experiments/ppo_primitives_relocalize_bc.yaml only in the teacher's
    loop-closing threshold, and configs/experiments/ppo_belief_cnn_relocalize_bc.yaml from that only in the observation's
    reader: the belief image and the CNN extractor."""

    home, shipped, mlp, cnn = (
        _large_entry("ppo_primitives_home_keep_bc"),
        _large_entry("ppo_primitives_relocalize03_bc"),
        _large_entry("ppo_primitives_relocalize_bc"),
        _large_entry("ppo_belief_cnn_relocalize_bc"),
    )
    assert home["pretrain"]["path"] is None
    assert home["pretrain"]["planner_kwargs"] == {"home_weight": 0.5}
    assert home["pretrain"]["keep_cloning"] == {"batches": 8, "learning_rate": 3.0e-5, "decay": 0.97}
    home["pretrain"].update(planner_kwargs={"relocalize_std": 0.3}, keep_cloning=None)
    assert home == shipped
    assert shipped["env_kwargs"]["reward"] == {"collision": 5.0, "pose_variance": 8.0}
    assert shipped["pretrain"]["planner_kwargs"] == {"relocalize_std": 0.3}
    assert mlp["pretrain"]["planner_kwargs"] == {"relocalize_std": 0.2}
    shipped["pretrain"]["planner_kwargs"] = {"relocalize_std": 0.2}
    assert shipped == mlp
    assert cnn["policy"] == "MultiInputPolicy" and mlp["policy"] == "MlpPolicy"
    assert cnn["policy_kwargs"].pop("features_extractor_class") == "ekfslam_gym.agents.extractors.BeliefCNN"
    cnn["policy_kwargs"].pop("features_extractor_kwargs")
    assert cnn["env_kwargs"].pop("observation")["belief_image"] is True
    assert cnn["normalize"].pop("norm_obs_keys")
    cnn["policy"] = mlp["policy"]
    assert cnn == mlp


def test_the_recurrent_home_keep_recipe_is_the_mlp_one_with_the_lstm_and_early_stopping():
    """configs/experiments/ppo_lstm_primitives_home_keep_bc.yaml is configs/experiments/ppo_primitives_home_keep_bc.yaml (the MLP recipe
    shipped before the recurrent one) with the recurrent recipe's policy (the algorithm, LSTM, minibatch and
    learning rate of configs/experiments/ppo_lstm_primitives_relocalize03_bc.yaml) and best_epoch; from that recurrent recipe
    it differs only in the teacher, the hold and best_epoch."""

    lstm_home, mlp_home, lstm = (
        _large_entry("ppo_lstm_primitives_home_keep_bc"),
        _large_entry("ppo_primitives_home_keep_bc"),
        _large_entry("ppo_lstm_primitives_relocalize03_bc"),
    )
    assert lstm_home["algo"] == "ppo_lstm" and lstm_home["pretrain"]["best_epoch"] is True
    policy_keys = ("algo", "policy", "policy_kwargs", "batch_size", "learning_rate")
    assert {k: lstm_home[k] for k in policy_keys} == {k: lstm[k] for k in policy_keys}
    assert any(lstm_home[k] != mlp_home[k] for k in policy_keys)
    mlp_home_like = {**lstm_home, **{k: mlp_home[k] for k in policy_keys}}
    mlp_home_like["pretrain"] = {**lstm_home["pretrain"], "best_epoch": False}
    assert mlp_home_like == mlp_home
    lstm_like = dict(lstm_home)
    lstm_like["pretrain"] = {**lstm_home["pretrain"], "planner_kwargs": {"relocalize_std": 0.3},
                             "keep_cloning": None, "best_epoch": False}  # fmt: skip
    assert lstm_like == lstm


def test_the_shipped_large_model_records_the_recurrent_recipe_at_pose_variance_4():
    """models/ppo_EKFSLAM-Large-v0.zip was trained from configs/ppo_lstm_primitives_home_keep_pv4_bc.yaml: its
    record holds that entry, less where its demonstrations were read (a file the same settings had collected,
    under the reward of pose_variance 8, reweighted). That config and the one at 6 shipped before it are
    configs/experiments/ppo_lstm_primitives_home_keep_bc.yaml with the pose-variance charge at 4 and 6 instead of 8, and
    nothing else."""
    import yaml

    pv4, pv6, lstm_home = (
        _large_entry("ppo_lstm_primitives_home_keep_pv4_bc"),
        _large_entry("ppo_lstm_primitives_home_keep_pv6_bc"),
        _large_entry("ppo_lstm_primitives_home_keep_bc"),
    )
    record = yaml.safe_load(Path("models/ppo_EKFSLAM-Large-v0_config.yaml").read_text())
    assert record["env_id"] == "EKFSLAM-Large-v0" and record["entry"]["algo"] == "ppo_lstm"
    assert record["seed"] == 1
    assert pv4["pretrain"]["path"] is None
    assert record["entry"]["pretrain"].pop("path").endswith("demonstrations.npz")
    record["entry"]["pretrain"]["path"] = None
    assert record["entry"] == pv4
    assert pv4["env_kwargs"]["reward"] == {"collision": 5.0, "pose_variance": 4.0}
    assert pv6["env_kwargs"]["reward"] == {"collision": 5.0, "pose_variance": 6.0}
    assert lstm_home["env_kwargs"]["reward"] == {"collision": 5.0, "pose_variance": 8.0}
    for charged in (pv4, pv6):
        charged["env_kwargs"]["reward"]["pose_variance"] = 8.0
        assert charged == lstm_home


def test_the_recurrent_belief_cnn_recipe_is_the_shipped_large_one_reading_the_image(tmp_path):
    """configs/experiments/ppo_lstm_belief_cnn_home_keep_pv4_bc.yaml is configs/ppo_lstm_primitives_home_keep_pv4_bc.yaml
    (models/ppo_EKFSLAM-Large-v0.zip's recipe) with the Dict observation's belief image read by BeliefCNN in a
    MultiInputLstmPolicy, and nothing else; at smoke size its demonstrations are cloned into that policy with
    one DAgger round, and PPO starts from the clone."""
    from ekfslam_gym.agents import PPOAgent
    from ekfslam_gym.agents.extractors import BeliefCNN

    cnn, shipped = (
        _large_entry("ppo_lstm_belief_cnn_home_keep_pv4_bc"),
        _large_entry("ppo_lstm_primitives_home_keep_pv4_bc"),
    )
    assert cnn["policy"] == "MultiInputLstmPolicy" and shipped["policy"] == "MlpLstmPolicy"
    assert cnn["policy_kwargs"].pop("features_extractor_class") == "ekfslam_gym.agents.extractors.BeliefCNN"
    cnn["policy_kwargs"].pop("features_extractor_kwargs")
    assert cnn["env_kwargs"].pop("observation")["belief_image"] is True
    assert "belief_image" not in cnn["normalize"].pop("norm_obs_keys")  # the image is already in [0, 1]
    assert cnn["normalize"] == shipped["normalize"]
    cnn["normalize"] = shipped["normalize"]
    cnn["policy"] = shipped["policy"]
    assert cnn == shipped

    out = tmp_path / "run"
    pretrain = (
        "{planner: frontier, planner_kwargs: {home_weight: 0.5}, episodes: 2, epochs: 2, dagger_rounds: 1, "
        "dagger_episodes: 1, best_epoch: true}"
    )
    config = "configs/experiments/ppo_lstm_belief_cnn_home_keep_pv4_bc.yaml"
    _smoke_train(config, out, pretrain, "primitives", "EKFSLAM-Large-v0")
    assert json.loads((out / "pretrain.json").read_text())["pairs"] == 24
    for name in ("bc_model.zip", "model.zip"):
        agent = PPOAgent(out / name)
        assert type(agent.model).__name__ == "RecurrentPPO" and agent.recurrent
        assert isinstance(agent.model.policy.features_extractor, BeliefCNN)
