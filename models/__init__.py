"""The shipped policies, one per registered env, as package data (``ekfslam_gym.packaged.shipped_model``)."""
