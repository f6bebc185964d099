"""The training recipes (rl-zoo3-style YAMLs) as package data (``ekfslam_gym.packaged.resolve_config``)."""
