"""Recorded drives replayed through EKF-SLAM: every replay returns one ``Replay`` (``result``).

By data set: ``course`` (the Freiburg course's files and the simulated drive, ``data.course``), ``chain`` (a GTSAM
2-D file whose odometry is one chain, Victoria Park), ``mrclam`` (a UTIAS MRCLAM robot's drive on one clock and
its settings, ``ReplaySettings``, built on ``filter.FilterSettings``), ``formats`` (which of those a path holds).
Then, for real data: ``innovations`` (each re-observation's NIS, compiled), ``figures`` (NIS against its band,
landmark errors after alignment, time per step: the figures every report prints), ``smoother`` (the full-SLAM
smoother on the same data and the one comparison with the filter), ``pictures``, ``calibration`` (noise fitted
by maximum likelihood of the innovations) and ``real`` (a data set from its path to its figures, what
``ekfslam-replay`` runs). Nothing is imported here: a replay of course files loads neither SciPy nor matplotlib.
"""
