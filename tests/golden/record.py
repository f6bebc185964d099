"""Record the seeded rollouts that ``tests/envs/test_golden_rollouts.py`` holds the env to.

Run once, before a refactor, with ``python tests/golden/record.py``: it writes ``rollouts.npz`` beside this
file (observations and rewards of a 500-step rollout of every registered id, seed 123, actions from a seeded
generator independent of the observations). A later change that alters behaviour fails the test.

Two settings are held: ``previous`` (the filter settings the first recording was made with, before the package
was reorganised: turn-drive-turn odometry, pose prior 1e-6; keys ``<env id>/...``) and ``default`` (the
defaults since the wheels model became the default; keys ``default/<env id>/...``).
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

import ekfslam_gym  # noqa: F401  (registers the ids)

ENV_IDS = ("EKFSLAM-v0", "EKFSLAM-Loop-v0", "EKFSLAM-Large-v0")
STEPS = 500
SEED = 123
HERE = Path(__file__).resolve().parent
SETTINGS = {
    "previous": {"filter": {"motion_model": "odometry", "pose_prior": 1e-6}},
    "default": {},
}
PREFIX = {"previous": "", "default": "default/"}


def actions(steps: int = STEPS, seed: int = 0) -> np.ndarray:
    """Random (v, omega) commands, each held for 1-10 steps: jittery and smooth driving both appear."""
    rng = np.random.default_rng(seed)
    out = np.empty((steps, 2), dtype=np.float32)
    t = 0
    while t < steps:
        hold = int(rng.integers(1, 11))
        out[t : t + hold] = rng.uniform(-1, 1, 2)
        t += hold
    return out


def rollout(env_id: str, setting: str = "default") -> dict[str, np.ndarray]:
    env = gym.make(env_id, **SETTINGS[setting])
    obs, info = env.reset(seed=SEED)
    observations, rewards, flags, log_dets = [obs], [], [], [info["log_det"]]
    for action in actions():
        obs, reward, terminated, truncated, info = env.step(action)
        observations.append(obs)
        rewards.append(reward)
        flags.append((terminated, truncated))
        log_dets.append(info["log_det"])
        if terminated or truncated:
            obs, info = env.reset()
            observations.append(obs)
            log_dets.append(info["log_det"])
    env.close()
    return {
        "observations": np.asarray(observations, dtype=np.float32),
        "rewards": np.asarray(rewards, dtype=np.float64),
        "flags": np.asarray(flags, dtype=bool),
        "log_dets": np.asarray(log_dets, dtype=np.float64),
    }


def main(settings: tuple[str, ...] = tuple(SETTINGS)) -> None:
    """Record ``settings`` (all by default), keeping what the file holds for the others."""
    path = HERE / "rollouts.npz"
    arrays = dict(np.load(path)) if path.exists() else {}
    for setting in settings:
        for env_id in ENV_IDS:
            for key, value in rollout(env_id, setting).items():
                arrays[f"{PREFIX[setting]}{env_id}/{key}"] = value
    np.savez_compressed(path, **arrays)
    print(f"wrote {HERE / 'rollouts.npz'}")


if __name__ == "__main__":
    import sys

    main(tuple(sys.argv[1:]) or tuple(SETTINGS))
