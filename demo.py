"""The main job (``make demo``): everything ekfslam-gym does, end to end, on its built-in defaults.

    python demo.py [--out out] [--timesteps 30000] [--seeds 10000-10004] [--smoke]

1. replays the project's own simulated drive through the EKF-SLAM and draws the belief (out/replay.png);
2. trains a short PPO run on EKFSLAM-v0 with configs/ppo.yaml (out/ppo_short/, with its learning curve);
3. compares the baselines, the short run and the shipped model (models/ppo_EKFSLAM-v0.zip) on held-out seeds
   (out/comparison.md, printed) and writes a GIF of the shipped policy (out/gifs/).

``--smoke`` shrinks every stage to seconds (the test suite runs it).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent
SHIPPED = ROOT / "models" / "ppo_EKFSLAM-v0.zip"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--out", type=Path, default=Path("out"))
    parser.add_argument("--timesteps", type=int, default=30_000, help="steps of the short PPO run")
    parser.add_argument("--seeds", default="10000-10004", help="held-out seeds for the comparison")
    parser.add_argument("--gif-seed", default="10001", help="held-out seed of the GIF (the README's)")
    parser.add_argument("--smoke", action="store_true", help="tiny settings, for tests")
    args = parser.parse_args(argv)
    out = args.out
    out.mkdir(parents=True, exist_ok=True)

    import train
    from ekfslam_gym.cli import evaluate, replay

    print("== 1. EKF-SLAM replay of the simulated drive", flush=True)
    replay_args = ["--plot", str(out / "replay.png")]
    if replay.main(replay_args + (["--steps", "50"] if args.smoke else [])) != 0:
        return 1

    print("\n== 2. A short PPO run on EKFSLAM-v0", flush=True)
    steps = 256 if args.smoke else args.timesteps
    hyper = (
        ["n_steps=32", "batch_size=64", "n_envs=2", "eval_freq=0", "checkpoint_freq=0"] if args.smoke else []
    )
    run = out / "ppo_short"
    train.main(["--config", str(ROOT / "configs" / "ppo.yaml"), "--timesteps", str(steps), "--out", str(run),
                *(["--hyperparams", *hyper] if hyper else [])])  # fmt: skip
    print(f"learning curve: {run / 'learning_curve.png'}")

    print("\n== 3. Baselines and PPO on held-out seeds", flush=True)
    seeds = "10000-10000" if args.smoke else args.seeds
    models = ["--model", str(run / "model.zip")]
    if SHIPPED.is_file():
        models += ["--model", str(SHIPPED)]
    else:
        print(f"(no shipped model at {SHIPPED}: comparing the short run only)")
    # Progress bars are drawn only on a terminal (train.py, evaluate): a log or a pipe gets plain lines.
    common = ["--seeds", seeds, *(["--max-episode-steps", "30"] if args.smoke else [])]
    status = evaluate.main(["--compare", "--per-model", *models, *common, "--table", str(out / "comparison.md"),
                            "--plot", str(out / "comparison.png")])  # fmt: skip
    if status != 0:
        return status
    print((out / "comparison.md").read_text())
    policy = SHIPPED if SHIPPED.is_file() else run / "model.zip"
    gif_seed = seeds.split("-")[0] if args.smoke else args.gif_seed
    status = evaluate.main(["--agent", "ppo", "--model", str(policy), "--seeds", gif_seed,
                            "--gif", str(out / "gifs"), "--gif-stride", "4", *common[2:]])  # fmt: skip
    print(
        f"\nwrote {out / 'replay.png'}, {out / 'comparison.md'}, {out / 'comparison.png'} and {out / 'gifs'}/"
    )
    return status


if __name__ == "__main__":
    sys.exit(main())
