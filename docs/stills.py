"""Draw one still image per registered env with the env's own ``rgb_array`` renderer: docs/images/<id>.png.

    python docs/stills.py [--steps-fraction 0.6] [--seed 10001]

The nearest-frontier planner drives each env from held-out seed 10001 for a fraction of its step limit, so the
picture shows the belief mid-episode: the true world in black and grey, the estimates with their 3-sigma
ellipses in blue, the estimated robot and its ellipse in red, the region the sensor sees shaded, and the
frame's legend naming each. One picture per id the package registers. Figures for reporting, never for tuning.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

IMAGES = Path(__file__).resolve().parent / "images"


def registered_ids() -> list[str]:
    """Every env id the package registers."""
    from gymnasium.envs.registration import registry

    import ekfslam_gym  # noqa: F401

    return [i for i, spec in registry.items() if str(spec.entry_point).startswith("ekfslam_gym.")]


def still(env_id: str, seed: int, fraction: float, path: Path) -> Path:
    """Drive ``env_id`` with the frontier planner for ``fraction`` of its step limit and save the frame."""
    import gymnasium as gym
    import imageio.v3 as iio
    from ekfslam_gym.agents import make_agent

    import ekfslam_gym  # noqa: F401  (registers the ids)
    from ekfslam_gym.envs.episode import step_limit

    env = gym.make(env_id, render_mode="rgb_array")
    agent = make_agent("frontier")
    obs, _ = env.reset(seed=seed)
    agent.reset(env, seed=seed)
    for _ in range(int(fraction * step_limit(env.unwrapped.config))):
        obs, _, terminated, truncated, _ = env.step(agent.act(obs))
        if terminated or truncated:
            break
    frame = env.render()
    env.close()
    path.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(path, frame)
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seed", type=int, default=10001)
    parser.add_argument("--steps-fraction", type=float, default=0.6)
    args = parser.parse_args(argv)
    for env_id in registered_ids():
        print(f"wrote {still(env_id, args.seed, args.steps_fraction, IMAGES / f'{env_id}.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
