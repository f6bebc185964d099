"""Train PPO on an EKFSLAM env from configs/ppo.yaml: a thin script over ``ekfslam_gym.cli.train`` (see its
docstring, or ``python train.py --help``).

    python train.py --config configs/ppo.yaml [--env-id ID] [--timesteps N] [--seed S] [--n-envs K]
                    [--out DIR] [--resume DIR] [--hyperparams KEY=VALUE ...] [--no-progress]

The implementation lives in the installed package (``ekfslam_gym.training``) so that code without this
repository's root on its path (a pip install, the sweep's Ray workers) can train too.
"""

from __future__ import annotations

from ekfslam_gym.cli.train import main

__all__ = ["main"]

if __name__ == "__main__":
    raise SystemExit(main())
