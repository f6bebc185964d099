"""The training recipes (rl-zoo3-style YAMLs) as package data (``ekfslam_gym.packaged.resolve_config``)."""

# The checkout's configs/ folder is the package ekfslam_gym.configs (setup.py maps it there): refuse the top-level name.
if __name__ != "ekfslam_gym.configs":
    raise ImportError(
        f"the checkout's configs/ folder installs as ekfslam_gym.configs: import that, not {__name__}"
    )
