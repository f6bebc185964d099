"""``python -m ekfslam_gym.compare``: the entry point of paired comparisons; the command line is
``ekfslam_gym.cli.compare``."""

from .cli.compare import main

if __name__ == "__main__":
    raise SystemExit(main())
