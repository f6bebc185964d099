"""``python -m ekfslam_gym.smoothing``: kept as an entry point; the command line is ``ekfslam_gym.cli.smoothing``."""

from .cli.smoothing import main

if __name__ == "__main__":
    raise SystemExit(main())
