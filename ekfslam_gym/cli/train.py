"""``ekfslam-train``: the installed twin of the repository's ``train.py`` (same options, same code,
``ekfslam_gym.agents.training``); ``--config`` takes a packaged recipe by name (``ppo``) or a path.

    ekfslam-train --config ppo_primitives --env-id EKFSLAM-Loop-v0 --seed 0 --out runs/loop0
"""

from __future__ import annotations

from collections.abc import Sequence


def main(argv: Sequence[str] | None = None) -> int:
    from ekfslam_gym.agents.training import main as train

    train(None if argv is None else list(argv))
    return 0
