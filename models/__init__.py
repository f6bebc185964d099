"""The shipped policies, one per registered env, as package data (``ekfslam_gym.packaged.shipped_model``)."""

# The checkout's models/ folder is the package ekfslam_gym.models (setup.py maps it there): refuse the top-level name.
if __name__ != "ekfslam_gym.models":
    raise ImportError(
        f"the checkout's models/ folder installs as ekfslam_gym.models: import that, not {__name__}"
    )
