"""``python -m ekfslam_gym.evaluate``: kept as an entry point; the command line is ``ekfslam_gym.cli.evaluate``."""

from .cli.evaluate import main

if __name__ == "__main__":
    raise SystemExit(main())
