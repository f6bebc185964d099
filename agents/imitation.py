"""Behaviour cloning of planner demonstrations into an SB3 PPO or sb3-contrib RecurrentPPO policy: the warm start of
planner-guided training.

Imitation first, then RL (issue 8): the policy is trained to choose the planner's action (the negative
log-likelihood ``evaluate_actions`` gives under the policy's own distribution: cross-entropy on a primitives
env's Discrete action, the diagonal Gaussian's on a waypoint env's Box goal; in shuffled minibatches over a few
epochs; a recurrent policy reads whole episodes, so that its LSTM can learn what the planner remembers and the
observation does not show, such as the frontier it heads for or that it is driving back to re-localise), and
optionally its value head to predict the discounted return the demonstrations earned, so that PPO's first
advantages are not those of an untrained critic. Before that, the VecNormalize statistics are
fitted to the demonstrations (observations, and the discounted returns the reward normaliser divides by), so
the policy is cloned on the inputs PPO fine-tuning will feed it.

``pretrain(model, env_id, entry, out)`` is what ``ekfslam_gym.agents.training`` runs before ``learn()`` when the config's
``train_settings`` hold a ``pretrain`` section (``PRETRAIN_DEFAULTS`` lists its keys); ``validate_pretrain``
checks that section. torch and stable-baselines3 are imported only when cloning.
"""

from __future__ import annotations

import copy
import json
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ekfslam_gym.seeds import (
    DEMONSTRATION_SEED_START,
    EVAL_SEED_START,
    SELECTION_EPISODES,
    check_demonstration_seeds,
    selection_seeds,
)

from .demonstrations import (
    PLANNERS,
    Demonstrations,
    collect,
    concatenate,
    env_reward_weights,
    load,
    reweighted,
    save,
)
from .ppo import is_recurrent

PRETRAIN_DEFAULTS: dict[str, Any] = {
    "planner": "greedy",  # the demonstrator (ekfslam_gym.agents.demonstrations.PLANNERS)
    "planner_kwargs": None,  # keyword arguments of the demonstrator, e.g. {relocalize_std: 0.2} for frontier
    "episodes": 200,  # demonstration episodes, one per seed from ``seed``
    "seed": DEMONSTRATION_SEED_START,  # first demonstration seed: a training range, clear of the held-out and evaluation seeds
    "epochs": 10,  # passes over the demonstrations
    "batch_size": 256,  # pairs per minibatch; a recurrent policy's holds whole episodes, about as many pairs
    "learning_rate": 1.0e-3,  # Adam's, for cloning only (PPO keeps its own optimiser)
    "holdout": 0.1,  # fraction of the demonstration episodes held back to report accuracy on
    "value": True,  # also fit the value head to the demonstrations' discounted (normalised) returns
    "best_epoch": False,  # keep the epoch whose weights best predict the held-back episodes (early stopping)
    "path": None,  # a demonstrations .npz to reuse instead of collecting (same env id and env_kwargs; a reward may differ)
    "dagger_rounds": 0,  # DAgger rounds after cloning: the clone drives, the planner labels, clone again
    "dagger_episodes": 50,  # episodes per DAgger round, on the seeds after seed + episodes (path: those too)
    "keep_cloning": None,  # cloning steps kept up during PPO (ekfslam_gym.agents.keep_cloning): {batches, learning_rate, decay}
}
KEEP_CLONING_DEFAULTS: dict[str, Any] = {
    "batches": 8,  # minibatches of the demonstrations after each rollout, one Adam step each
    "learning_rate": 3.0e-5,  # Adam's rate for them at the first rollout
    "decay": 1.0,  # the rate's factor per rollout (DAPG's lambda_1); 1 holds the clone near its teacher throughout
}
BOX_MATCH = 0.1  # a cloned Box action within this distance of the planner's counts as a match (accuracy)
DEMONSTRATIONS_FILE = "demonstrations.npz"
DAGGER_FILE = "dagger.npz"  # the demonstrations and every DAgger round's pairs, when there were rounds
BC_MODEL = "bc_model"  # the cloned policy, before any PPO update, saved with its statistics in the run folder


def with_defaults(value: Any, defaults: Mapping[str, Any], name: str) -> dict[str, Any] | None:
    """A settings section ``name`` over its ``defaults``: None when absent or false, all defaults when true,
    else the mapping's keys over the defaults; ValueError for anything else or for a key not in ``defaults``."""
    if value is None or value is False:
        return None
    if value is True:
        value = {}
    if not isinstance(value, Mapping):
        raise ValueError(f"{name} must be a mapping of {sorted(defaults)} (or absent), got {value!r}")
    unknown = sorted(set(value) - set(defaults))
    if unknown:
        raise ValueError(f"unknown {name} keys {unknown}; known: {sorted(defaults)}")
    return {**defaults, **value}


def validate_pretrain(value: Any, entry: Mapping[str, Any] | None = None) -> dict[str, Any] | None:
    """The ``pretrain`` setting with its defaults filled in, or None when absent or false; ValueError naming
    the key for anything else. With ``entry``, the demonstration seeds are also checked against its
    evaluation seeds (``eval_seed`` onwards, ``eval_episodes`` of them)."""
    settings = with_defaults(value, PRETRAIN_DEFAULTS, "pretrain")
    if settings is None:
        return None
    if settings["planner"] not in PLANNERS:
        raise ValueError(f"pretrain.planner must be one of {list(PLANNERS)}, got {settings['planner']!r}")
    for key, low in (("episodes", 1), ("seed", 0), ("epochs", 1), ("batch_size", 1), ("dagger_rounds", 0),
                     ("dagger_episodes", 1)):  # fmt: skip
        if isinstance(settings[key], bool) or not isinstance(settings[key], int) or settings[key] < low:
            raise ValueError(f"pretrain.{key} must be an integer >= {low}, got {settings[key]!r}")
    rate = settings["learning_rate"]
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not rate > 0:
        raise ValueError(f"pretrain.learning_rate must be a positive number, got {rate!r}")
    holdout = settings["holdout"]
    if isinstance(holdout, bool) or not isinstance(holdout, (int, float)) or not 0 <= holdout < 1:
        raise ValueError(f"pretrain.holdout must be a fraction in [0, 1), got {holdout!r}")
    for key in ("value", "best_epoch"):
        if not isinstance(settings[key], bool):
            raise ValueError(f"pretrain.{key} must be true or false, got {settings[key]!r}")
    if settings["best_epoch"] and not holdout > 0:
        raise ValueError("pretrain.best_epoch picks an epoch by the held-back episodes: it needs holdout > 0")
    kwargs = settings["planner_kwargs"]
    if kwargs is not None and not (isinstance(kwargs, Mapping) and all(isinstance(k, str) for k in kwargs)):
        raise ValueError(f"pretrain.planner_kwargs must be a mapping of keyword arguments, got {kwargs!r}")
    if settings["path"] is not None and not isinstance(settings["path"], str):
        raise ValueError(f"pretrain.path must be a file name or null, got {settings['path']!r}")
    settings["keep_cloning"] = validate_keep_cloning(settings["keep_cloning"])
    eval_seeds = range(0) if entry is None else run_selection_seeds(entry)
    try:
        check_demonstration_seeds(demonstration_seeds(settings, -1), eval_seeds)
    except ValueError as error:
        raise ValueError(f"pretrain.seed/episodes: {error}") from None
    if entry is not None and "env_kwargs" in entry:
        action = (entry.get("env_kwargs") or {}).get("action") or {}
        kind = action.get("kind", "velocity") if isinstance(action, Mapping) else None
        if kind not in PLANNERS[settings["planner"]]:
            raise ValueError(
                f"pretrain.planner {settings['planner']!r} demonstrates in action.kind "
                f"{' or '.join(map(repr, PLANNERS[settings['planner']]))}, but env_kwargs' action.kind is {kind!r}"
            )
    else:
        kind = PLANNERS[settings["planner"]][-1]
    if kwargs:
        from .demonstrations import make_planner

        try:  # the constructor checks its own arguments (the env is needed only at reset)
            make_planner(settings["planner"], kind, **kwargs)
        except (TypeError, ValueError) as error:
            raise ValueError(f"pretrain.planner_kwargs: {error}") from None
    return settings


def validate_keep_cloning(value: Any) -> dict[str, Any] | None:
    """``pretrain.keep_cloning`` with its defaults filled in, or None when absent or false."""
    settings = with_defaults(value, KEEP_CLONING_DEFAULTS, "pretrain.keep_cloning")
    if settings is None:
        return None
    batches = settings["batches"]
    if isinstance(batches, bool) or not isinstance(batches, int) or batches < 1:
        raise ValueError(f"pretrain.keep_cloning.batches must be an integer >= 1, got {batches!r}")
    rate, decay = settings["learning_rate"], settings["decay"]
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not rate > 0:
        raise ValueError(f"pretrain.keep_cloning.learning_rate must be a positive number, got {rate!r}")
    if isinstance(decay, bool) or not isinstance(decay, (int, float)) or not 0 < decay <= 1:
        raise ValueError(f"pretrain.keep_cloning.decay must be in (0, 1], got {decay!r}")
    return settings


def run_selection_seeds(entry: Mapping[str, Any]) -> range:
    """The evaluation seeds a run's entry selects its model on (``eval_seed`` onwards, ``eval_episodes``)."""
    return selection_seeds(
        entry.get("eval_seed", EVAL_SEED_START), entry.get("eval_episodes", SELECTION_EPISODES)
    )


def demonstration_seeds(settings: Mapping[str, Any], round_: int | None = None) -> range:
    """The planner's seeds (``round_`` None), those of DAgger round ``round_`` (0, 1, ...), or with ``round_`` -1
    all of them: one block of consecutive seeds from ``seed``."""
    first, n, per = int(settings["seed"]), int(settings["episodes"]), int(settings.get("dagger_episodes", 0))
    if round_ is None:
        return range(first, first + n)
    if round_ < 0:
        return range(first, first + n + int(settings.get("dagger_rounds", 0)) * per)
    start = first + n + round_ * per
    return range(start, start + per)


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
    from stable_baselines3.common.utils import obs_as_tensor

    discrete = isinstance(model.action_space, spaces.Discrete)
    if not discrete and not isinstance(model.action_space, spaces.Box):
        raise ValueError(f"behaviour cloning needs a Discrete or Box action space, got {model.action_space}")
    if demos.actions.shape[1:] != model.action_space.shape:
        raise ValueError(f"demonstrated actions of shape {demos.actions.shape[1:]} do not fit the policy's "
                         f"{model.action_space}")  # fmt: skip
    if len(demos) == 0:
        raise ValueError("no demonstrations to clone")
    start = time.perf_counter()
    policy = model.policy
    rng = np.random.default_rng(seed)
    normalizer = model.get_vec_normalize_env()
    observations = demos.observations
    rewards = demos.rewards
    if normalizer is not None:
        observations = normalizer.normalize_obs(observations)
        rewards = normalizer.normalize_reward(rewards)
    targets = returns_to_go(rewards, demos.episodes, float(model.gamma))
    actions = demos.actions.astype(np.int64 if discrete else np.float32)
    if held is None:
        train_idx, hold_idx = split_episodes(demos.episodes, holdout, rng)
    else:
        train_idx, hold_idx = np.flatnonzero(~held), np.flatnonzero(held)

    def take(index: np.ndarray) -> Any:
        if isinstance(observations, Mapping):
            return obs_as_tensor({k: v[index] for k, v in observations.items()}, policy.device)
        return obs_as_tensor(observations[index], policy.device)

    batcher = (SequenceBatches if is_recurrent(policy) else PairBatches)(policy, demos.episodes)

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
            act = torch.as_tensor(actions[batch], device=policy.device)
            values, log_prob = batcher.evaluate(take(batch), act, n_seq)
            weight = torch.as_tensor(mask, dtype=log_prob.dtype, device=policy.device)
            n = float(mask.sum())
            loss_a = -(log_prob.flatten() * weight).sum() / n
            loss = loss_a
            loss_v = torch.zeros(())
            if value:
                target = torch.as_tensor(targets[batch], dtype=values.dtype, device=policy.device)
                loss_v = (((values.flatten() - target) ** 2) * weight).sum() / n
                loss = loss + float(model.vf_coef) * loss_v
            optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(policy.parameters(), float(model.max_grad_norm))
            optimizer.step()
            sums += [loss_a.item() * n, loss_v.item() * n]
            pairs += int(n)
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


# ---------------------------------------------------------------------------------------------- training hook
def demonstrations_for(
    env_id: str, entry: Mapping[str, Any], settings: Mapping[str, Any], out: Path
) -> Demonstrations:
    """The run's demonstrations: ``settings["path"]`` if given, else collected and saved in ``out`` as
    ``demonstrations.npz``. A file must be of the run's env id and env_kwargs; only the ``reward`` may differ,
    and then its rewards are recomputed under the run's weights (``reweighted``), since the weights change the
    reward and never the trajectory."""
    env_kwargs = dict(entry.get("env_kwargs") or {})
    if settings.get("path"):
        demos = load(settings["path"])
        recorded = (demos.meta.get("env_id"), demos.meta.get("env_kwargs"))
        if recorded == (env_id, env_kwargs):
            return demos
        if recorded[0] != env_id or _without_reward(recorded[1] or {}) != _without_reward(env_kwargs):
            raise ValueError(
                f"{settings['path']} holds demonstrations of {recorded[0]} with env_kwargs {recorded[1]}, "
                f"this run trains {env_id} with {env_kwargs}"
            )
        try:
            demos = reweighted(demos, env_reward_weights(env_id, env_kwargs))
        except ValueError as error:
            raise ValueError(f"{settings['path']}: {error}") from None
        demos.meta.update(env_kwargs=env_kwargs, reweighted_from=str(settings["path"]))
        return demos
    demos = collect(env_id, demonstration_seeds(settings), env_kwargs, planner=settings["planner"],
                    planner_kwargs=settings["planner_kwargs"], eval_seeds=run_selection_seeds(entry))  # fmt: skip
    save(demos, Path(out) / DEMONSTRATIONS_FILE)
    return demos


def _without_reward(env_kwargs: Mapping[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in env_kwargs.items() if k != "reward"}


def pretrain(model: Any, env_id: str, entry: Mapping[str, Any], out: Path) -> dict[str, Any] | None:
    """The ``pretrain`` step of a training run (no-op without the setting): demonstrations, normalisation
    statistics fitted to them, behaviour cloning, then ``dagger_rounds`` DAgger rounds (the clone drives
    ``dagger_episodes`` episodes, the planner labels the observations it reaches, the clone is trained again on
    everything; Ross, Gordon & Bagnell 2011). Writes ``pretrain.json`` (settings, one ``CloneReport`` per
    round, and per DAgger round the fraction of the clone's own decisions that matched the planner's) and the
    cloned policy as ``bc_model.zip`` (with its statistics and the run's config) in ``out``; with DAgger, the
    aggregated pairs as ``dagger.npz``."""
    settings = validate_pretrain(entry.get("pretrain"), entry)
    if settings is None:
        return None
    from .ppo import PPOAgent
    from .training import save_with_stats

    out = Path(out)
    start = time.perf_counter()
    demos = demonstrations_for(env_id, entry, settings, out)
    collected = time.perf_counter() - start
    reused = set(demos.seeds.tolist()) & set(demonstration_seeds(settings, -1)[settings["episodes"] :])
    if reused:
        raise ValueError(
            f"DAgger seeds {sorted(reused)[:5]} are among the demonstrations' own; move pretrain.seed"
        )
    rng = np.random.default_rng(settings["seed"])
    held = np.isin(
        demos.episodes, demos.episodes[split_episodes(demos.episodes, settings["holdout"], rng)[1]]
    )
    normalizer = model.get_vec_normalize_env()

    def clone(epochs: int) -> CloneReport:
        if normalizer is not None:
            fit_normalizer(normalizer, demos)
        return behaviour_clone(model, demos, epochs=epochs, batch_size=settings["batch_size"],
                               learning_rate=settings["learning_rate"], value=settings["value"],
                               seed=settings["seed"], held=held, best_epoch=settings["best_epoch"])  # fmt: skip

    reports = [clone(settings["epochs"])]
    agreement = []
    for round_ in range(settings["dagger_rounds"]):
        tick = time.perf_counter()
        more = collect(env_id, demonstration_seeds(settings, round_), dict(entry.get("env_kwargs") or {}),
                       planner=settings["planner"], planner_kwargs=settings["planner_kwargs"],
                       driver=PPOAgent(model=model, vecnormalize=normalizer),
                       eval_seeds=run_selection_seeds(entry))  # fmt: skip
        collected += time.perf_counter() - tick
        # The clone drove deterministically, so its accuracy on what it reached is its agreement with the planner.
        on_policy = behaviour_clone(model, more, epochs=0, held=np.ones(len(more), dtype=bool))
        agreement.append(on_policy.holdout_accuracy)
        split = split_episodes(more.episodes, settings["holdout"], rng)[1]
        held = np.concatenate([held, np.isin(more.episodes, more.episodes[split])])
        demos = concatenate(demos, more)
        reports.append(clone(settings["epochs"]))
    if settings["dagger_rounds"]:
        save(demos, out / DAGGER_FILE)
    save_with_stats(model, out / BC_MODEL, out)
    record = {"settings": dict(settings), "pairs": len(demos), "episodes": int(len(demos.seeds)),
              "demonstration_seconds": collected, "clone": asdict(reports[-1]),
              "rounds": [asdict(r) for r in reports], "dagger_agreement": agreement}  # fmt: skip
    (out / "pretrain.json").write_text(json.dumps(record, indent=2))
    return record
