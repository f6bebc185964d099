"""Action interfaces: what one env step means (``action.kind`` in the env config).

Learned exploration beats planners when the policy decides at the level of goals or motion primitives and a
controller drives (Chaplot et al., "Learning to explore using Active Neural SLAM", ICLR 2020: long-range goals
re-decided every 25 steps; Cao et al., ARiADNE, ICRA 2023: the choice of viewpoint). So besides the raw
command the env offers two macro actions, each driven for up to ``action.hold`` control steps of ``dt``:

- ``velocity`` (default): ``Box(-1, 1, (2,))``, (forward speed, turn rate) as fractions of the robot's limits,
  held for ``hold`` control steps (default 1: one env step is one control step).
- ``primitives``: ``Discrete(K)``, one of ``PRIMITIVES`` (the greedy planner's motion primitives), held for
  ``hold`` control steps (default 10); with ``action.guard`` g m (default 0: off), a control step whose forward
  travel would bring the robot within g of a wall the scan shows ahead keeps only the primitive's turn, and
  one that finds the robot already within g of it backs off while keeping the turn.
- ``waypoint``: ``Box(-1, 1, (2,))``, a goal (forward, left) x ``waypoint_radius`` m relative to the *estimated*
  pose when the step begins, driven by ``WaypointController`` from the pose estimate and the wall scan only
  (never the true pose or map) until it reaches the goal, a wall in the scan blocks it, or ``hold`` (default
  10) control steps have passed.

A macro step's reward is the sum of its control steps' rewards, in order; ``info["reward_terms"]`` holds
each term summed over them (the information-gain terms still telescope), ``info["inner_steps"]`` how many
ran and ``info["inner_actions"]`` the (forward, turn) commands they applied. The step limit
(``max_episode_steps``) counts env steps, as every wrapper and library does; a registered id's limit is divided
by ``hold`` when none is given, so that an episode lasts the same simulated time (``ekfslam_gym.envs.horizon``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from .config import ACTION_KINDS, DEFAULT_HOLD
from .waypoint import WaypointController, goal_in_world

__all__ = [
    "ACTION_KINDS",
    "DEFAULT_HOLD",
    "PRIMITIVES",
    "ActionInterface",
    "clipped_velocity",
    "make_interface",
]

# (v / v_max, omega / omega_max): straight, gentle and sharp arcs both ways, turning in place both ways.
PRIMITIVES: tuple[tuple[float, float], ...] = (
    (1.0, 0.0),
    (1.0, 0.25),
    (1.0, -0.25),
    (1.0, 0.5),
    (1.0, -0.5),
    (0.5, 1.0),
    (0.5, -1.0),
    (0.0, 1.0),
    (0.0, -1.0),
)


def clipped_velocity(action: Any) -> tuple[float, float]:
    """(forward, turn) as floats clipped to [-1, 1]; ValueError, before anything changes, for a wrong shape or
    a non-finite value. A float array of shape (2,), what agents pass, takes the fast path."""
    if type(action) is np.ndarray and action.shape == (2,) and action.dtype.kind == "f":
        a0, a1 = action.tolist()
    else:
        a = np.asarray(action, dtype=np.float64)
        if a.shape != (2,):
            raise ValueError(f"action must have shape (2,), got {a.shape}")
        a0, a1 = float(a[0]), float(a[1])
    if not (math.isfinite(a0) and math.isfinite(a1)):
        raise ValueError(f"action must be finite, got {action!r}")
    return (
        -1.0 if a0 < -1.0 else 1.0 if a0 > 1.0 else a0,
        -1.0 if a1 < -1.0 else 1.0 if a1 > 1.0 else a1,
    )


class ActionInterface:
    """Turns one env action into control steps. ``begin`` checks the action (ValueError before anything
    changes) and fixes what the whole macro step needs; ``command`` gives the next control step's (forward,
    turn), or None to end the macro step early; ``encode`` writes the action ``begin`` took, as
    ``observation.last_action`` holds it."""

    space: gym.Space

    def begin(self, action: Any, pose_estimate: np.ndarray) -> None:
        raise NotImplementedError

    def encode(self, out: np.ndarray) -> None:
        raise NotImplementedError

    def command(
        self, pose_estimate: np.ndarray, scan_of: Callable[[], np.ndarray]
    ) -> tuple[float, float] | None:
        raise NotImplementedError


class HeldVelocity(ActionInterface):
    """The raw (forward, turn) command, held."""

    def __init__(self) -> None:
        self.space = gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self._command = (0.0, 0.0)

    def begin(self, action: Any, pose_estimate: np.ndarray) -> None:
        self._command = clipped_velocity(action)

    def encode(self, out: np.ndarray) -> None:
        out[:] = self._command

    def command(self, pose_estimate: np.ndarray, scan_of: Callable[[], np.ndarray]) -> tuple[float, float]:
        return self._command


class MotionPrimitives(ActionInterface):
    """One of ``PRIMITIVES`` by index, held."""

    def __init__(self) -> None:
        self.space = gym.spaces.Discrete(len(PRIMITIVES))
        self._index = 0
        self._command = PRIMITIVES[0]

    def begin(self, action: Any, pose_estimate: np.ndarray) -> None:
        index = np.asarray(action)
        if index.shape not in ((), (1,)) or index.dtype.kind not in "iu":
            raise ValueError(f"a primitives action is one integer in [0, {len(PRIMITIVES)}), got {action!r}")
        index = int(index.reshape(()))
        if not 0 <= index < len(PRIMITIVES):
            raise ValueError(f"a primitives action is one integer in [0, {len(PRIMITIVES)}), got {index}")
        self._index = index
        self._command = PRIMITIVES[index]

    def encode(self, out: np.ndarray) -> None:
        """A one-hot of the primitive."""
        out[:] = 0.0
        out[self._index] = 1.0

    def command(self, pose_estimate: np.ndarray, scan_of: Callable[[], np.ndarray]) -> tuple[float, float]:
        return self._command


class GuardedPrimitives(MotionPrimitives):
    """``MotionPrimitives`` with ``action.guard``: a control step whose forward travel (``step`` m at full speed)
    would bring the robot within ``guard`` m of a wall the scan shows ahead, as ``controller`` measures the room
    ahead, keeps only the primitive's turn; one that finds the robot already within ``guard`` of it backs off,
    turn kept (``_backoff``). The robot stops short of the wall, as a waypoint does, instead of sliding along
    it (each contact step costs the wheel odometry a slip of 0.35 m per m commanded, ``WheelOdometryNoise``).
    A class of its own, so that unguarded primitives pay nothing for it."""

    def __init__(self, guard: float, controller: WaypointController, step: float) -> None:
        super().__init__()
        self.guard = float(guard)
        self.controller = controller
        self.step = float(step)
        # Nothing the scan shows can stop the step when every beam ends farther than this: the disc reaches a
        # wall point r m away only after r - radius m, and a joined segment lies at most join / 2 nearer.
        self._far = controller.radius + 0.5 * controller.join + self.guard + self.step

    def command(self, pose_estimate: np.ndarray, scan_of: Callable[[], np.ndarray]) -> tuple[float, float]:
        forward, turn = self._command
        if forward > 0.0:
            scan = scan_of()
            if scan.min() < self._far:
                ahead = self.controller.clearance_ahead(scan)
                if ahead < self.guard + forward * self.step:
                    return self._backoff(scan) if ahead < self.guard else 0.0, turn
        return self._command

    def _backoff(self, scan: np.ndarray) -> float:
        """The forward command of a step that finds the robot already within the guard of a wall ahead: the
        scan's beams (16 by default) can miss a wall's end between two of them until the robot is upon it, and a
        turn can sweep a wall alongside into the way. It backs off at the controller's ``backoff`` speed while
        the scan shows room behind, else stands; without this a policy whose forward primitives are stopped
        can stay against the wall, turning to and fro."""
        behind = self.controller.clearances(scan)[1]
        return -self.controller.backoff if behind > self.guard + self.controller.backoff * self.step else 0.0


class Waypoint(ActionInterface):
    """A goal relative to the estimated pose, driven by the scan-only waypoint controller."""

    def __init__(self, controller: WaypointController, radius: float) -> None:
        self.space = gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.controller = controller
        self.radius = radius
        self.goal = (0.0, 0.0)
        self._action = (0.0, 0.0)

    def begin(self, action: Any, pose_estimate: np.ndarray) -> None:
        self._action = forward, left = clipped_velocity(action)
        self.goal = goal_in_world(pose_estimate, forward * self.radius, left * self.radius)

    def encode(self, out: np.ndarray) -> None:
        """The clipped goal (forward, left), in units of the radius."""
        out[:] = self._action

    def command(
        self, pose_estimate: np.ndarray, scan_of: Callable[[], np.ndarray]
    ) -> tuple[float, float] | None:
        step = self.controller.command(pose_estimate, self.goal, scan_of())
        if step.reached or step.blocked:
            return None
        return step.v, step.omega


def make_interface(config) -> ActionInterface:
    """The action interface of an ``EnvConfig`` (its ``action`` section)."""
    kind = config.action.kind
    if kind == "velocity":
        return HeldVelocity()
    if kind == "primitives":
        if not config.action.guard:
            return MotionPrimitives()
        controller = WaypointController.from_config(config, margin=0.0)
        return GuardedPrimitives(config.action.guard, controller, config.robot.v_max * config.dt)
    return Waypoint(WaypointController.from_config(config), config.action.waypoint_radius)
