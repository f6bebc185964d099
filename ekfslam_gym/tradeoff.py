"""``python -m ekfslam_gym.tradeoff``: the entry point of trade-off plots; the command line is
``ekfslam_gym.cli.tradeoff``."""

from .cli.tradeoff import main

if __name__ == "__main__":
    raise SystemExit(main())
