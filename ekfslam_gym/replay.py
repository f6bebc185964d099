"""``python -m ekfslam_gym.replay``: kept as an entry point; the command line is ``ekfslam_gym.cli.replay``."""

from .cli.replay import main

if __name__ == "__main__":
    raise SystemExit(main())
