"""``python -m ekfslam_gym.graph``: the graph-optimisation command line (``ekfslam_gym.cli.graph``)."""

from ..cli.graph import main

raise SystemExit(main())
