"""``python -m ekfslam_gym.sweep``: the entry point of training sweeps on Ray; the command line is
``ekfslam_gym.cli.sweep``."""

from .cli.sweep import main

if __name__ == "__main__":
    raise SystemExit(main())
