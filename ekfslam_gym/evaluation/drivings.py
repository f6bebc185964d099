"""The ways a policy drives, as action sequences, for measuring the filter's consistency under each
(``bench/consistency.py`` and ``tests/evaluation/test_consistency_mc.py``).

Each is (steps, 2) velocity actions in [-1, 1]^2, fractions of (v_max, omega_max), as a policy sends them to
the env: ``forward`` v ~ U[0, 1], omega ~ U[-1, 1] fresh every step (a fresh policy's jitter); ``random``
U[-1, 1]^2 every step; ``spin`` (0, 0.5), turning in place, and ``turn`` (0, 1), turning in place at the full
rate; ``held`` U[-1, 1]^2 held for 10 steps; ``circle`` v = 0.55 with omega for a 6.5 m circle (the blind
circle of ``ekfslam_gym.agents.baselines``, which slides along walls where the circle meets them).
"""

from __future__ import annotations

import numpy as np

from ..sim.robot import RobotParams

DRIVINGS = ("forward", "random", "spin", "turn", "held", "circle")
CIRCLE_SPEED, CIRCLE_RADIUS, HOLD = 0.55, 6.5, 10


def driving_actions(driving: str, rng: np.random.Generator, steps: int, robot: RobotParams) -> np.ndarray:
    """(steps, 2) actions of ``driving`` (``DRIVINGS``), random parts drawn from ``rng``."""
    if driving == "forward":
        actions = np.column_stack([rng.uniform(0.0, 1.0, steps), rng.uniform(-1.0, 1.0, steps)])
    elif driving == "random":
        actions = rng.uniform(-1.0, 1.0, (steps, 2))
    elif driving == "spin":
        actions = np.tile([0.0, 0.5], (steps, 1))
    elif driving == "turn":
        actions = np.tile([0.0, 1.0], (steps, 1))
    elif driving == "held":
        actions = np.repeat(rng.uniform(-1.0, 1.0, (steps // HOLD + 1, 2)), HOLD, axis=0)[:steps]
    elif driving == "circle":
        omega = CIRCLE_SPEED * robot.v_max / CIRCLE_RADIUS / robot.omega_max
        actions = np.tile([CIRCLE_SPEED, omega], (steps, 1))
    else:
        raise ValueError(f"unknown driving {driving!r}; known: {DRIVINGS}")
    return np.clip(actions, -1.0, 1.0)
