"""Behaviour cloning kept up during PPO fine-tuning, so that the clone stays near its teacher while PPO improves it.

Fine-tuned with PPO alone, a clone ends on the reward's own trade-off between certainty and accuracy, whichever
teacher it started from (docs/results.md, *A teacher off the curve*). Demo-augmented policy gradient (DAPG;
Rajeswaran et al., RSS 2018) keeps the demonstrations in every update, with a weight λ0·λ1^k that decays over
the iterations k. Here that is done between PPO's updates: after each rollout, before PPO's epochs, ``batches``
minibatches of the demonstrations (with DAgger, the aggregated set) each take one Adam step on the negative
log-likelihood of the planner's action, at the rate ``learning_rate``·``decay``^k for the run's k-th rollout
(k from the step count, so a resumed run continues the schedule). Only the policy's action is cloned; the value
head is left to PPO. The Adam optimiser is its own, so its moments are not mixed with PPO's gradients (a resumed
run starts it afresh).

``pretrain.keep_cloning`` in a training config switches it on (``settings.KEEP_CLONING_DEFAULTS``);
``ekfslam_gym.training.run`` adds ``KeepCloning`` to the run's callbacks. The cloning step and its minibatches
are behaviour cloning's own (``cloning.clone_step``). stable-baselines3 and torch are imported with this module.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback

from .artefacts import run_demonstrations
from .cloning import action_labels, batcher_for, clone_step, observation_batch
from .demonstrations import Demonstrations


def keep_cloning_rate(settings: Mapping[str, Any], rollout: int) -> float:
    """Adam's rate for the cloning steps after the ``rollout``-th rollout (0 for the first)."""
    return float(settings["learning_rate"]) * float(settings["decay"]) ** int(rollout)


class KeepCloning(BaseCallback):
    """After each rollout, ``settings["batches"]`` Adam steps of behaviour cloning on ``demos`` (see the module
    docstring). The observations are normalised by the model's VecNormalize as it stands then, as PPO's are.
    Minibatches of ``batch_size`` pairs (whole episodes for a recurrent policy) are drawn with a generator seeded
    by (``seed``, rollout), so a resumed run draws what the uninterrupted one would have."""

    def __init__(
        self, demos: Demonstrations, settings: Mapping[str, Any], *, batch_size: int, seed: int
    ) -> None:
        super().__init__()
        if len(demos) == 0:
            raise ValueError("no demonstrations to keep cloning")
        self.demos = demos
        self.settings = dict(settings)
        self.batch_size = int(batch_size)
        self.seed = int(seed)
        self.optimizer = None
        self.batcher = None

    def _init_callback(self) -> None:
        policy = self.model.policy
        self.actions = action_labels(self.demos, self.model.action_space)
        self.batcher = batcher_for(policy, self.demos.episodes)
        self.optimizer = torch.optim.Adam(policy.parameters(), lr=float(self.settings["learning_rate"]))

    def rollout_index(self) -> int:
        """The run's rollouts so far, less one: 0 at the end of the first."""
        per_rollout = int(self.model.n_steps) * int(self.model.n_envs)
        return max(self.model.num_timesteps // per_rollout - 1, 0)

    def clone_steps(self) -> float:
        """The cloning steps of the current rollout; returns their mean negative log-likelihood."""
        rollout = self.rollout_index()
        rate = keep_cloning_rate(self.settings, rollout)
        for group in self.optimizer.param_groups:
            group["lr"] = rate
        policy = self.model.policy
        rng = np.random.default_rng([self.seed, rollout])
        batches = self.batcher.minibatches(np.arange(len(self.demos)), self.batch_size, rng)
        policy.set_training_mode(True)
        losses = []
        normalizer = self.model.get_vec_normalize_env()
        for _, (batch, mask, n_seq) in zip(range(int(self.settings["batches"])), batches):
            observations = observation_batch(self.demos, batch, policy, normalizer)
            loss, _, _ = clone_step(policy, self.optimizer, self.batcher, observations, self.actions[batch], mask,
                                    n_seq, self.model.max_grad_norm)  # fmt: skip
            losses.append(loss)
        policy.set_training_mode(False)
        self.logger.record("keep_cloning/learning_rate", rate)
        self.logger.record("keep_cloning/nll", float(np.mean(losses)))
        return float(np.mean(losses))

    def _on_rollout_end(self) -> None:
        self.clone_steps()

    def _on_step(self) -> bool:
        return True


def keep_cloning_callback(model: Any, out: Path, pretrain: Mapping[str, Any] | None) -> KeepCloning | None:
    """The run's ``KeepCloning`` callback, or None when ``pretrain.keep_cloning`` is off."""
    if not pretrain or not pretrain.get("keep_cloning"):
        return None
    return KeepCloning(run_demonstrations(out, pretrain), pretrain["keep_cloning"],
                       batch_size=int(pretrain["batch_size"]), seed=int(pretrain["seed"]))  # fmt: skip
