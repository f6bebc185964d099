"""Behaviour cloning of planner demonstrations into an SB3 PPO or sb3-contrib RecurrentPPO policy: the warm start of
planner-guided training.

Imitation first, then RL: the policy is trained to choose the planner's action (the negative
log-likelihood ``evaluate_actions`` gives under the policy's own distribution: cross-entropy on a primitives
env's Discrete action, the diagonal Gaussian's on a waypoint env's Box goal; in shuffled minibatches over a few
epochs; a recurrent policy reads whole episodes, so that its LSTM can learn what the planner remembers and the
observation does not show, such as the frontier it heads for or that it is driving back to re-localise), and
optionally its value head to predict the discounted return the demonstrations earned, so that PPO's first
advantages are not those of an untrained critic. Before that, the VecNormalize statistics are
fitted to the demonstrations (observations, and the discounted returns the reward normaliser divides by), so
the policy is cloned on the inputs PPO fine-tuning will feed it.

``behaviour_clone`` clones a set of demonstrations; its minibatches (``batcher_for``: pairs, or whole episodes for
a recurrent policy), their observations (``observation_batch``) and its Adam step (``clone_step``) are the ones
``keep_cloning`` takes between PPO's updates too. ``ekfslam_gym.training.pretraining`` runs it before
``learn()``. torch and stable-baselines3 are imported only when cloning.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ekfslam_gym.agents.ppo import is_recurrent

from .demonstrations import Demonstrations

BOX_MATCH = 0.1  # a cloned Box action within this distance of the planner's counts as a match (accuracy)


# ---------------------------------------------------------------------------------------------- normalisation
def fit_normalizer(vec_normalize: Any, demos: Demonstrations) -> None:
    """Set a VecNormalize's statistics from the demonstrations: the observation mean and variance (per key of
    a Dict observation) and, when it normalises rewards, those of the discounted return it divides by, replayed
    episode by episode as VecNormalize accumulates it (``returns = gamma * returns + reward``)."""
    from stable_baselines3.common.running_mean_std import RunningMeanStd

    def fitted(data: np.ndarray) -> RunningMeanStd:
        rms = RunningMeanStd(shape=data.shape[1:])
        rms.mean = np.mean(data, axis=0, dtype=np.float64)
        rms.var = np.var(data, axis=0, dtype=np.float64)
        rms.count = float(len(data))
        return rms

    if vec_normalize.norm_obs:
        if isinstance(vec_normalize.obs_rms, dict):
            vec_normalize.obs_rms = {key: fitted(demos.observations[key]) for key in vec_normalize.obs_rms}
        else:
            vec_normalize.obs_rms = fitted(demos.observations)
    if vec_normalize.norm_reward:
        vec_normalize.ret_rms = fitted(discounted_running_returns(demos, vec_normalize.gamma))


def discounted_running_returns(demos: Demonstrations, gamma: float) -> np.ndarray:
    """VecNormalize's running discounted return after each step, restarting with each episode."""
    out = np.empty(len(demos))
    running, episode = 0.0, None
    for i, (reward, k) in enumerate(zip(demos.rewards, demos.episodes)):
        running = (0.0 if k != episode else gamma * running) + reward
        episode = k
        out[i] = running
    return out


def returns_to_go(rewards: np.ndarray, episodes: np.ndarray, gamma: float) -> np.ndarray:
    """The discounted sum of the rewards from each step to its episode's end (the value-head target)."""
    out = np.empty(len(rewards))
    running = 0.0
    for i in range(len(rewards) - 1, -1, -1):
        if i == len(rewards) - 1 or episodes[i + 1] != episodes[i]:
            running = 0.0
        running = rewards[i] + gamma * running
        out[i] = running
    return out


# ---------------------------------------------------------------------------------------------- cloning
@dataclass
class CloneReport:
    """What cloning achieved: accuracy on the pairs it was trained on and on the held-back episodes (NaN when
    none), and the mean losses of the epoch kept. Accuracy: the fraction of pairs whose most likely action is the
    planner's (Discrete), or lies within ``BOX_MATCH`` of it (Box, Euclidean, in the action's units).
    ``holdout_by_epoch`` is the held-back accuracy before the first epoch and after each (empty when nothing is
    held back); ``kept_epoch`` is the epoch whose weights the policy ends with (``epochs`` unless ``best_epoch``
    chose an earlier one; 0 is the weights cloning started from), and the accuracies above are theirs."""

    train_pairs: int
    holdout_pairs: int
    holdout_episodes: int
    train_accuracy: float
    holdout_accuracy: float
    action_loss: float
    value_loss: float
    epochs: int
    seconds: float
    holdout_by_epoch: list[float]
    kept_epoch: int


def split_episodes(
    episodes: np.ndarray, holdout: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """(train, held-back) pair indices: whole episodes are held back (``holdout`` of them, at least one when
    ``holdout`` > 0 and there are two or more; pairs within one episode are too alike to test on)."""
    ids = np.unique(episodes)
    n_hold = 0
    if holdout > 0 and len(ids) >= 2:
        n_hold = min(max(1, int(round(holdout * len(ids)))), len(ids) - 1)
    held = rng.choice(ids, size=n_hold, replace=False) if n_hold else np.array([], dtype=ids.dtype)
    mask = np.isin(episodes, held)
    return np.flatnonzero(~mask), np.flatnonzero(mask)


class PairBatches:
    """Minibatches of single (observation, action) pairs, for a feed-forward policy: each is a flat array of
    ``size`` pair indices (shuffled with ``rng``, in order without), an all-true mask, and no sequence count."""

    def __init__(self, policy: Any, episodes: np.ndarray) -> None:
        self.policy = policy

    def minibatches(self, index: np.ndarray, size: int, rng: np.random.Generator | None):
        order = index if rng is None else rng.permutation(index)
        for first in range(0, len(order), size):
            batch = order[first : first + size]
            yield batch, np.ones(len(batch), dtype=bool), None

    def evaluate(self, obs: Any, actions: Any, n_seq: None) -> tuple[Any, Any]:
        values, log_prob, _ = self.policy.evaluate_actions(obs, actions)
        return values, log_prob

    def deterministic_actions(self, obs: Any, n_seq: None) -> np.ndarray:
        return self.policy.get_distribution(obs).get_actions(deterministic=True).cpu().numpy()


class SequenceBatches:
    """Minibatches of whole episodes, for a recurrent policy: the LSTM must read an episode from its first step,
    as it did when the planner's episode was driven. A batch of n episodes is an (n, T) array of pair indices,
    flattened episode by episode as sb3-contrib's ``_process_sequence`` unflattens it; episodes shorter than the
    longest, T, are padded with their last pair, and the mask excludes the padding (the LSTM is causal, so the
    padding after an episode's end cannot change its earlier outputs). Every sequence starts from a zero LSTM
    state, so no step is marked as an episode start and the LSTM runs over the batch in one call. A batch holds
    about ``size`` pairs: ``size`` over the mean episode length, at least one episode."""

    def __init__(self, policy: Any, episodes: np.ndarray) -> None:
        self.policy = policy
        self.episodes = episodes
        order = np.argsort(episodes, kind="stable")  # pairs are stored in time order within an episode
        ids, first = np.unique(episodes[order], return_index=True)
        self.steps = dict(zip(ids.tolist(), np.split(order, first[1:])))

    def minibatches(self, index: np.ndarray, size: int, rng: np.random.Generator | None):
        ids = np.unique(self.episodes[index])
        if rng is not None:
            ids = rng.permutation(ids)
        lengths = np.array([len(self.steps[k]) for k in ids.tolist()])
        per_batch = max(1, int(round(size / max(float(np.mean(lengths)), 1.0)))) if len(ids) else 1
        for first in range(0, len(ids), per_batch):
            chosen = [self.steps[k] for k in ids[first : first + per_batch].tolist()]
            longest = max(len(steps) for steps in chosen)
            padded = np.stack([np.pad(steps, (0, longest - len(steps)), mode="edge") for steps in chosen])
            mask = np.arange(longest)[None, :] < np.array([len(steps) for steps in chosen])[:, None]
            yield padded.reshape(-1), mask.reshape(-1), len(chosen)

    def _zero_states(self, n_seq: int) -> Any:
        import torch
        from sb3_contrib.common.recurrent.type_aliases import RNNStates

        layers, _, hidden = self.policy.lstm_hidden_state_shape
        zeros = torch.zeros((layers, n_seq, hidden), device=self.policy.device)
        return RNNStates((zeros, zeros), (zeros, zeros))

    def _starts(self, obs: Any) -> Any:
        import torch

        n = len(next(iter(obs.values()))) if isinstance(obs, Mapping) else len(obs)
        return torch.zeros(n, device=self.policy.device)

    def evaluate(self, obs: Any, actions: Any, n_seq: int) -> tuple[Any, Any]:
        states = self._zero_states(n_seq)
        values, log_prob, _ = self.policy.evaluate_actions(obs, actions, states, self._starts(obs))
        return values, log_prob

    def deterministic_actions(self, obs: Any, n_seq: int) -> np.ndarray:
        states = self._zero_states(n_seq)
        distribution, _ = self.policy.get_distribution(obs, states.pi, self._starts(obs))
        return distribution.get_actions(deterministic=True).cpu().numpy()


def batcher_for(policy: Any, episodes: np.ndarray) -> PairBatches | SequenceBatches:
    """The minibatches ``policy`` is cloned on: single pairs, or whole episodes for a recurrent policy."""
    return (SequenceBatches if is_recurrent(policy) else PairBatches)(policy, episodes)


def action_labels(demos: Demonstrations, action_space: Any) -> np.ndarray:
    """The demonstrated actions as the policy's log-likelihood takes them (int64 indices of a Discrete space,
    float32 goals of a Box); ValueError when they do not fit ``action_space``."""
    from gymnasium import spaces

    discrete = isinstance(action_space, spaces.Discrete)
    if not discrete and not isinstance(action_space, spaces.Box):
        raise ValueError(f"behaviour cloning needs a Discrete or Box action space, got {action_space}")
    if demos.actions.shape[1:] != action_space.shape:
        raise ValueError(f"demonstrated actions of shape {demos.actions.shape[1:]} do not fit the policy's "
                         f"{action_space}")  # fmt: skip
    return demos.actions.astype(np.int64 if discrete else np.float32)


def observation_batch(demos: Demonstrations, index: np.ndarray, policy: Any, normalizer: Any = None) -> Any:
    """The observations at ``index`` as the policy reads them: normalised by ``normalizer`` (a VecNormalize, as
    it stands now) if given, as tensors on the policy's device (a dict of them for a Dict observation)."""
    from stable_baselines3.common.utils import obs_as_tensor

    batch = demos.take(index)
    if normalizer is not None:
        batch = normalizer.normalize_obs(batch)
    return obs_as_tensor(batch, policy.device)


def clone_step(
    policy: Any,
    optimizer: Any,
    batcher: PairBatches | SequenceBatches,
    observations: Any,
    actions: np.ndarray,
    mask: np.ndarray,
    n_seq: int | None,
    max_grad_norm: float,
    value_targets: np.ndarray | None = None,
    vf_coef: float = 0.0,
) -> tuple[float, float, int]:
    """One Adam step of behaviour cloning on a minibatch: the mean negative log-likelihood of the demonstrated
    ``actions`` over the pairs ``mask`` keeps, plus, with ``value_targets``, ``vf_coef`` times the value head's
    mean squared error; one gradient-norm clip (``max_grad_norm`` over every parameter, as SB3's PPO update
    does). Returns (action loss, value loss or 0, pairs)."""
    import torch

    values, log_prob = batcher.evaluate(observations, torch.as_tensor(actions, device=policy.device), n_seq)
    weight = torch.as_tensor(mask, dtype=log_prob.dtype, device=policy.device)
    n = float(mask.sum())
    loss_a = -(log_prob.flatten() * weight).sum() / n
    loss = loss_a
    loss_v = torch.zeros(())
    if value_targets is not None:
        target = torch.as_tensor(value_targets, dtype=values.dtype, device=policy.device)
        loss_v = (((values.flatten() - target) ** 2) * weight).sum() / n
        loss = loss + float(vf_coef) * loss_v
    optimizer.zero_grad()
    loss.backward()
    torch.nn.utils.clip_grad_norm_(policy.parameters(), float(max_grad_norm))
    optimizer.step()
    return loss_a.item(), loss_v.item(), int(n)


def behaviour_clone(
    model: Any,
    demos: Demonstrations,
    *,
    epochs: int = 10,
    batch_size: int = 256,
    learning_rate: float = 1.0e-3,
    holdout: float = 0.1,
    value: bool = True,
    seed: int = 0,
    held: np.ndarray | None = None,
    best_epoch: bool = False,
) -> CloneReport:
    """Train ``model.policy`` (an SB3 actor-critic on a Discrete or Box action space, feed-forward or sb3-contrib's
    recurrent one, which is trained on whole episodes: ``SequenceBatches``) to choose the demonstrated
    actions; the observations are normalised by the model's VecNormalize, if any (fit it first:
    ``fit_normalizer``). With ``value``, the value head also regresses the demonstrations' discounted returns
    (rewards normalised as the VecNormalize would, discounted with ``model.gamma``). ``held`` (bool per pair)
    fixes the held-back pairs, else ``holdout`` of the episodes are drawn with ``seed``, which also orders the
    minibatches; torch's global generator is left alone, so the run's own seed still drives PPO afterwards.
    With ``best_epoch``, the policy ends with the weights of the epoch (0 included: those it started from) of
    highest held-back accuracy, the earliest on ties: early stopping, for a policy that overfits the pairs it is
    trained on (a recurrent one cloned again after a DAgger round). The held-back accuracy is measured after
    every epoch either way; it draws nothing at random, so it leaves the cloning as it was. The action and value
    losses share one gradient-norm clip (``max_grad_norm`` over every parameter, as SB3's PPO update does), so
    the rewards reach the cloned actions through the value loss's size: one demonstrations file cloned under two
    reward settings gives two clones (with ``value=False``, one)."""
    import torch
    from gymnasium import spaces

    actions = action_labels(demos, model.action_space)
    discrete = isinstance(model.action_space, spaces.Discrete)
    if len(demos) == 0:
        raise ValueError("no demonstrations to clone")
    start = time.perf_counter()
    policy = model.policy
    rng = np.random.default_rng(seed)
    normalizer = model.get_vec_normalize_env()
    rewards = demos.rewards if normalizer is None else normalizer.normalize_reward(demos.rewards)
    targets = returns_to_go(rewards, demos.episodes, float(model.gamma))
    if held is None:
        train_idx, hold_idx = split_episodes(demos.episodes, holdout, rng)
    else:
        train_idx, hold_idx = np.flatnonzero(~held), np.flatnonzero(held)

    def take(index: np.ndarray) -> Any:
        return observation_batch(demos, index, policy, normalizer)

    batcher = batcher_for(policy, demos.episodes)

    def accuracy(index: np.ndarray) -> float:
        if len(index) == 0:
            return float("nan")
        matches = []
        for batch, mask, n_seq in batcher.minibatches(index, 8192, None):
            with torch.no_grad():
                chosen = batcher.deterministic_actions(take(batch), n_seq)[mask]
            wanted = actions[batch][mask]
            if discrete:
                matches.append(chosen.reshape(-1) == wanted)
            else:
                low, high = model.action_space.low, model.action_space.high
                matches.append(np.linalg.norm(np.clip(chosen, low, high) - wanted, axis=1) <= BOX_MATCH)
        return float(np.mean(np.concatenate(matches)))

    if best_epoch and len(hold_idx) == 0:
        raise ValueError("best_epoch chooses the epoch on the held-back episodes, and none are held back")

    def measure() -> None:
        """Records the held-back accuracy of the weights as they are; keeps them if best so far."""
        nonlocal kept, kept_state
        if len(hold_idx) == 0:
            return
        policy.set_training_mode(False)
        curve.append(accuracy(hold_idx))
        policy.set_training_mode(True)
        if best_epoch and curve[-1] > curve[kept]:
            kept, kept_state = len(curve) - 1, copy.deepcopy(policy.state_dict())

    curve: list[float] = []
    kept, kept_state = 0, copy.deepcopy(policy.state_dict()) if best_epoch else None
    optimizer = torch.optim.Adam(policy.parameters(), lr=float(learning_rate))
    policy.set_training_mode(True)
    measure()
    losses = [(float("nan"), float("nan"))]  # each epoch's mean (action, value) losses, none before the first
    for _ in range(int(epochs)):
        sums, pairs = np.zeros(2), 0
        for batch, mask, n_seq in batcher.minibatches(train_idx, int(batch_size), rng):
            loss_a, loss_v, n = clone_step(policy, optimizer, batcher, take(batch), actions[batch], mask, n_seq,
                                           model.max_grad_norm, targets[batch] if value else None, model.vf_coef)  # fmt: skip
            sums += [loss_a * n, loss_v * n]
            pairs += n
        losses.append(tuple((sums / max(pairs, 1)).tolist()))
        measure()
    if not best_epoch:
        kept = int(epochs)
    elif kept < int(epochs):
        policy.load_state_dict(kept_state)
    policy.set_training_mode(False)
    action_loss, value_loss = losses[kept]
    return CloneReport(
        train_pairs=int(len(train_idx)), holdout_pairs=int(len(hold_idx)),
        holdout_episodes=int(len(np.unique(demos.episodes[hold_idx]))), train_accuracy=accuracy(train_idx),
        holdout_accuracy=curve[kept] if curve else float("nan"), action_loss=action_loss,
        value_loss=value_loss if value else float("nan"), epochs=int(epochs),
        seconds=time.perf_counter() - start, holdout_by_epoch=curve, kept_epoch=kept,
    )  # fmt: skip
