"""The wall veto of a motion primitive: the wall scan as points and joined segments in the robot frame, the arc a
primitive drives, and its clearance from them (the planners never use the walls' true geometry). Poses relative
to a robot are (forward, left, heading change), m and rad."""

from __future__ import annotations

import math

import numpy as np

WALL_JOIN = 1.5  # m: neighbouring scan end points closer than this are taken to lie on one surface


def arc_poses(v: float, omega: float, dt: float, steps: int) -> np.ndarray:
    """The poses (steps + 1, 3) relative to the start that ``v`` (m/s) and ``omega`` (rad/s) held for ``steps``
    steps of ``dt`` s reach in free space: each step a chord v dt sinc(omega dt / 2) at the mid-step heading."""
    half = 0.5 * omega * dt
    chord = v * dt * (math.sin(half) / half if abs(half) > 1e-9 else 1.0)
    poses = np.zeros((steps + 1, 3))
    for k in range(steps):
        x, y, theta = poses[k]
        poses[k + 1] = (
            x + chord * math.cos(theta + half),
            y + chord * math.sin(theta + half),
            theta + 2 * half,
        )
    return poses


def scan_geometry(scan: np.ndarray, angles: np.ndarray, scan_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Wall points (m, 2) and segments (s, 4) in the robot frame from the scan (m per beam at ``angles``; a range
    at or beyond ``scan_max`` hit nothing)."""
    hit = scan < scan_max - 1e-6
    points = np.column_stack([scan * np.cos(angles), scan * np.sin(angles)])
    nxt = np.roll(np.arange(scan.size), -1)
    join = hit & hit[nxt] & (np.hypot(*(points[nxt] - points).T) < WALL_JOIN)
    segments = np.concatenate([points[join], points[nxt][join]], axis=1)
    return points[hit], segments


def clearances(rel: np.ndarray, points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Distance (m) from each relative position (K, 3) to the nearest scanned wall point or segment."""
    d = np.full(rel.shape[0], np.inf)
    if points.size:
        d = np.min(
            np.hypot(rel[:, None, 0] - points[None, :, 0], rel[:, None, 1] - points[None, :, 1]), axis=1
        )
    if segments.size:
        a, b = segments[:, :2], segments[:, 2:]
        ab = b - a
        t = np.einsum("ksd,sd->ks", rel[:, None, :2] - a[None], ab) / np.maximum(
            np.sum(ab * ab, axis=1), 1e-12
        )
        closest = a[None] + np.clip(t, 0.0, 1.0)[..., None] * ab[None]
        d = np.minimum(d, np.min(np.linalg.norm(rel[:, None, :2] - closest, axis=2), axis=1))
    return d


def arc_vetoed(
    rel: np.ndarray,
    pose: np.ndarray,
    points: np.ndarray,
    segments: np.ndarray,
    safe: float,
    bounds: np.ndarray,
    radius: float,
) -> bool:
    """Whether the path ``rel`` (K, 3; relative to ``pose``, from the origin or, for a second primitive, from the
    first's end) is ruled out: it comes within ``safe`` m of a scanned wall and closer than where it starts, or
    leaves the world's ``bounds`` (xmin, ymin, xmax, ymax; a robot of ``radius`` m) unless it starts outside and
    comes back. Turning in place never is."""
    if np.allclose(rel[:, :2], rel[0, :2]):
        return False  # turning in place never hits anything (from the origin, or from a first step's end)
    d = clearances(rel, points, segments)
    ahead = d[1:].min()
    if ahead < safe and ahead < d[0]:
        return True
    world = to_world(rel, pose)
    xmin, ymin, xmax, ymax = bounds
    margin = (
        np.minimum.reduce([world[:, 0] - xmin, xmax - world[:, 0], world[:, 1] - ymin, ymax - world[:, 1]])
        - radius
    )
    return bool(margin[1:].min() < 0.0 and margin[1:].min() < margin[0])


def to_world(rel: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Poses (K, 3) relative to ``pose`` in the world frame."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    out = np.empty_like(rel)
    out[:, 0] = pose[0] + c * rel[:, 0] - s * rel[:, 1]
    out[:, 1] = pose[1] + s * rel[:, 0] + c * rel[:, 1]
    out[:, 2] = pose[2] + rel[:, 2]
    return out
