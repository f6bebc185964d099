"""``python -m ekfslam_gym.consistency``: the entry point; the command line is ``ekfslam_gym.cli.consistency``."""

from .cli.consistency import main

if __name__ == "__main__":
    raise SystemExit(main())
