"""ekfslam-gym: active SLAM as a Gymnasium environment."""

__version__ = "0.1.0"
