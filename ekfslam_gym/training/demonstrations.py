"""Demonstrations of a planner in a macro action interface, for behaviour cloning.

The planners (``ekfslam_gym.agents.planners``) act in the policy's own interface, so their choices can be
imitated. ``collect`` drives the env with one and keeps the env's raw observations (before any VecNormalize),
the chosen actions, the rewards and each reward term (``info["reward_terms"]``); ``save``/``load`` keep them as
``.npz``. The reward's weights change only the reward, never the trajectory, so ``reweighted`` gives the same
demonstrations under another reward whose terms were recorded (a reward sweep collects them once).

Seeds: demonstrations are training data, so their seeds must avoid the held-out suite and the evaluation seeds
that select models (``ekfslam_gym.seeds``); ``collect`` checks them with ``check_demonstration_seeds``.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from ekfslam_gym.agents.base import ActionKind
from ekfslam_gym.agents.planners import make_planner
from ekfslam_gym.envs.config import RewardConfig
from ekfslam_gym.envs.rewards import REWARD_NAMES, nonzero_weights, weigh
from ekfslam_gym.seeds import SELECTION_SEEDS, check_demonstration_seeds


@dataclass
class Demonstrations:
    """(observation, action) pairs of a planner, with the episode each pair came from and its reward.

    ``observations`` is an array (N, ...) for a Box observation, a dict of them for a Dict observation (raw,
    as the env returns them); ``actions`` (N,) int64 primitive indices, or (N, 2) float32 waypoint goals;
    ``rewards`` (N,) float64, the env's reward for the step; ``episodes`` (N,) int64, the index into ``seeds``
    of the pair's episode; ``reward_terms`` every reward term of the step by name, unweighted
    (``info["reward_terms"]``; ``meta["reward_terms"] == "unweighted"``), and ``meta["reward_weights"]`` the
    weights the rewards were collected under. Files written before kept only the terms with a non-zero weight,
    weighted (no ``meta["reward_terms"]``), or none at all.
    """

    observations: Any
    actions: np.ndarray
    rewards: np.ndarray
    episodes: np.ndarray
    seeds: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)
    reward_terms: dict[str, np.ndarray] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.actions)

    def take(self, index: np.ndarray) -> Any:
        """The observations at ``index`` (an array, or a dict of arrays)."""
        if isinstance(self.observations, Mapping):
            return {k: v[index] for k, v in self.observations.items()}
        return self.observations[index]


def collect(
    env_id: str,
    seeds: Iterable[int],
    env_kwargs: Mapping[str, Any] | None = None,
    *,
    planner: str = "greedy",
    planner_kwargs: Mapping[str, Any] | None = None,
    eval_seeds: Iterable[int] = SELECTION_SEEDS,
    driver: Any = None,
) -> Demonstrations:
    """One episode of the planner per seed in ``env_id`` built as the trainer builds its envs
    (``gym.make(id, **env_kwargs)``, so ``max_episode_steps`` is gym.make's limit); the env must use the
    planner's action interfaces (``ekfslam_gym.agents.planners.PLANNERS``). Seeds are checked with ``check_demonstration_seeds``.

    With ``driver`` (an ``Agent``, e.g. the policy being cloned), the driver's actions are executed and the
    planner only labels each visited observation with its own choice: the states the learner reaches, labelled
    by the expert (DAgger; Ross, Gordon & Bagnell 2011). ``rewards`` are then the driven episode's."""
    import ekfslam_gym  # noqa: F401  (registers the env ids)

    seeds = check_demonstration_seeds(seeds, eval_seeds)
    if not seeds:
        raise ValueError("no demonstration seeds")
    qualified = env_id if ":" in env_id else f"ekfslam_gym:{env_id}"
    env = gym.make(qualified, **dict(env_kwargs or {}))
    observations: list[Any] = []
    actions, rewards, episodes = [], [], []
    weights = asdict(env.unwrapped.config.reward)  # every term's weight, defaults included
    terms: dict[str, list[float]] = {name: [] for name in REWARD_NAMES}
    kind = ActionKind.of_env(env)
    try:
        agent = make_planner(planner, kind, **dict(planner_kwargs or {}))
        for k, seed in enumerate(seeds):
            observation, _ = env.reset(seed=seed)
            agent.reset(env, seed=seed)
            if driver is not None:
                driver.reset(env, seed=seed)
            while True:
                label = agent.act(observation)
                action = label if driver is None else kind.action(driver.act(observation))
                agent.executed(action)
                observations.append(observation)
                actions.append(label)
                episodes.append(k)
                observation, reward, terminated, truncated, info = env.step(action)
                rewards.append(float(reward))
                for name, values in terms.items():  # unweighted, every term
                    values.append(float(info["reward_terms"][name]))
                if terminated or truncated:
                    break
    finally:
        env.close()
    if isinstance(observations[0], Mapping):
        stacked: Any = {key: np.stack([o[key] for o in observations]) for key in observations[0]}
    else:
        stacked = np.stack(observations)
    meta = {"env_id": env_id, "env_kwargs": dict(env_kwargs or {}), "planner": planner,
            "planner_kwargs": dict(planner_kwargs or {}),
            "driver": None if driver is None else getattr(driver, "name", type(driver).__name__),
            "reward_weights": weights, "reward_terms": "unweighted"}  # fmt: skip
    labels = np.asarray(actions, dtype=np.int64 if kind is ActionKind.PRIMITIVES else np.float32)
    return Demonstrations(stacked, labels, np.array(rewards, dtype=np.float64),
                          np.array(episodes, dtype=np.int64), np.array(seeds, dtype=np.int64), meta,
                          {name: np.array(values, dtype=np.float64) for name, values in terms.items()})  # fmt: skip


def env_reward_weights(env_id: str, env_kwargs: Mapping[str, Any] | None = None) -> dict[str, float]:
    """Every reward term's weight, by name, in the env ``gym.make(env_id, **env_kwargs)`` builds (the env id's
    preset and the defaults filled in)."""
    import ekfslam_gym  # noqa: F401  (registers the env ids)

    env = gym.make(env_id if ":" in env_id else f"ekfslam_gym:{env_id}", **dict(env_kwargs or {}))
    try:
        return asdict(env.unwrapped.config.reward)
    finally:
        env.close()


def reweighted(demos: Demonstrations, weights: Mapping[str, float]) -> Demonstrations:
    """``demos`` with the rewards the env would have given under ``weights`` (every term's weight by name, as
    ``env_reward_weights``): the sum of each recorded, unweighted term times its new weight, taken by the env's own
    ``rewards.weigh``. Exact up to rounding because a weight only multiplies its term and never changes the
    trajectory. ValueError when the new reward
    needs a term the demonstrations did not record (a file of the older, weighted kind whose weight for it was
    0, or one that predates the terms)."""
    recorded = {name: float(w) for name, w in demos.meta.get("reward_weights", {}).items()}
    weights = {name: float(weights.get(name, 0.0)) for name in REWARD_NAMES}
    if recorded == weights:
        return demos
    if not recorded:
        raise ValueError("the demonstrations predate the recorded reward terms; collect them again")
    if demos.meta.get("reward_terms") == "unweighted":
        terms = demos.reward_terms
    else:  # an older file: the terms with a non-zero weight, weighted
        terms = {
            name: values / recorded[name] for name, values in demos.reward_terms.items() if recorded.get(name)
        }
    missing = [name for name, w in weights.items() if w and name not in terms]
    if missing:
        raise ValueError(
            f"the demonstrations did not record the reward terms {missing} that this run's reward weighs "
            "(their weight was 0 when these older demonstrations were collected); collect them again"
        )
    # the env's own sum (``rewards.weigh``), taken over the recorded steps at once
    rewards = np.zeros(len(demos.actions)) + weigh(terms, nonzero_weights(RewardConfig(**weights)))
    meta = {**demos.meta, "reward_weights": weights, "reward_terms": "unweighted"}
    return Demonstrations(
        demos.observations, demos.actions, rewards, demos.episodes, demos.seeds, meta, terms
    )


def concatenate(first: Demonstrations, second: Demonstrations) -> Demonstrations:
    """``first`` then ``second`` as one set (``second``'s episodes numbered after ``first``'s); ``first``'s meta."""
    if isinstance(first.observations, Mapping):
        observations: Any = {
            k: np.concatenate([v, second.observations[k]]) for k, v in first.observations.items()
        }
    else:
        observations = np.concatenate([first.observations, second.observations])
    return Demonstrations(
        observations, np.concatenate([first.actions, second.actions]),
        np.concatenate([first.rewards, second.rewards]),
        np.concatenate([first.episodes, second.episodes + len(first.seeds)]),
        np.concatenate([first.seeds, second.seeds]), dict(first.meta),
        {k: np.concatenate([v, second.reward_terms[k]]) for k, v in first.reward_terms.items()
         if k in second.reward_terms},
    )  # fmt: skip


def save(demos: Demonstrations, path: str | Path) -> Path:
    """Write ``demos`` as ``.npz`` (Dict observations as ``obs/<key>`` arrays, the rest as ``meta`` JSON)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(demos.observations, Mapping):
        obs = {f"obs/{k}": v for k, v in demos.observations.items()}
    else:
        obs = {"obs": demos.observations}
    terms = {f"reward_terms/{k}": v for k, v in demos.reward_terms.items()}
    np.savez_compressed(path, actions=demos.actions, rewards=demos.rewards, episodes=demos.episodes,
                        seeds=demos.seeds, meta=np.array(json.dumps(demos.meta)), **obs, **terms)  # fmt: skip
    return path


def load(path: str | Path) -> Demonstrations:
    """Read what ``save`` wrote."""
    with np.load(path, allow_pickle=False) as data:
        if "obs" in data.files:
            observations: Any = data["obs"]
        else:
            observations = {name[4:]: data[name] for name in data.files if name.startswith("obs/")}
        terms = {name[13:]: data[name] for name in data.files if name.startswith("reward_terms/")}
        return Demonstrations(observations, data["actions"], data["rewards"], data["episodes"], data["seeds"],
                              json.loads(str(data["meta"])), terms)  # fmt: skip
