"""``ekfslam-train`` and ``python -m ekfslam_gym.train``: the training command line (``ekfslam_gym.cli.train``)
with bad input, from inside the run too, ended in one line (``command_line``), as ``train.py`` runs it."""

from .cli.common import command_line
from .cli.train import main as _main

main = command_line("train")(_main)

if __name__ == "__main__":
    raise SystemExit(main())
