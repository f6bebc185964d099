"""``python -m ekfslam_gym.benchmark``: the benchmark command line (``ekfslam_gym.cli.benchmark``)."""

from ..cli.benchmark import main

raise SystemExit(main())
