"""Record the seeded rollouts that ``tests/envs/test_golden_rollouts_v1.py`` holds the v1 ids to.

``python -m tests.golden.record_v1`` writes ``rollouts_v1.npz`` beside this file: the 500-step rollout of
``record.rollout`` (seed 123, seeded actions independent of the observations, the ids' own settings) of every
registered v1 id. The v0 recording (``rollouts.npz``) is not touched. A later change that alters a v1 id's
behaviour fails the test, and needs a new id version rather than a new recording.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

import ekfslam_gym  # noqa: F401  (registers the ids)
from tests.golden.record import rollout

HERE = Path(__file__).resolve().parent
PATH = HERE / "rollouts_v1.npz"


def v1_ids() -> list[str]:
    """Every registered v1 id, sorted."""
    return sorted(i for i in gym.registry if i.startswith("EKFSLAM") and i.endswith("-v1"))


def main(env_ids: tuple[str, ...] = ()) -> None:
    """Record ``env_ids`` (every v1 id by default), keeping what the file holds for the others."""
    arrays = dict(np.load(PATH)) if PATH.exists() else {}
    for env_id in env_ids or v1_ids():
        for key, value in rollout(env_id, "default").items():
            arrays[f"{env_id}/{key}"] = value
    np.savez_compressed(PATH, **arrays)
    print(f"wrote {PATH}")


if __name__ == "__main__":
    import sys

    main(tuple(sys.argv[1:]))
