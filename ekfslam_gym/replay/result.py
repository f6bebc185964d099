"""What every replay returns: the filter at the end, its path, and the innovation statistics of its readings."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..filter import EKFSLAM

__all__ = ["Replay"]


@dataclass(eq=False)  # holds arrays
class Replay:
    """A recorded drive replayed through EKF-SLAM.

    poses (T+1, 3): the estimate at the start and after each of the T steps. labels (n,): the landmark each
    slot holds, by the data set's own name for it (a course file's id, an MRCLAM subject, a GTSAM landmark
    index + 1), -1 where a slot holds none. nis (R,): each re-observation's NIS (2 dof) before its correction,
    and nis_at (R,) when it was read (the step's index, or its time in seconds where the data has a clock).
    log_likelihood: the sum over steps of log N(innovation; 0, S) of the re-observations jointly
    (``calibration``). seconds: the filter's own time (predictions and corrections, nothing else).
    false_associations, missed_associations, new_landmarks: unknown association counted against the data
    set's identities (0 with known association). extras: what a replay keeps for its pictures (a course
    replay's frames, its last readings and its true path).
    """

    ekf: EKFSLAM
    poses: np.ndarray
    labels: np.ndarray
    nis: np.ndarray = field(default_factory=lambda: np.zeros(0))
    nis_at: np.ndarray = field(default_factory=lambda: np.zeros(0))
    log_likelihood: float = 0.0
    seconds: float = 0.0
    false_associations: int = 0
    missed_associations: int = 0
    new_landmarks: int = 0
    extras: dict[str, Any] = field(default_factory=dict)

    @property
    def steps(self) -> int:
        """The number of steps replayed (predictions)."""
        return len(self.poses) - 1

    @property
    def microseconds_per_step(self) -> float:
        return 1e6 * self.seconds / max(self.steps, 1)

    def landmark_estimates(self) -> dict[int, np.ndarray]:
        """``{label: (x, y)}`` of the slots that hold an initialised landmark; with two slots for one label
        (unknown association may start a landmark twice), the one initialised first (lower slot)."""
        out: dict[int, np.ndarray] = {}
        for slot in np.flatnonzero(self.ekf.observed):
            label = int(self.labels[slot])
            if label > 0 and label not in out:
                out[label] = self.ekf.landmarks[slot].copy()
        return out
