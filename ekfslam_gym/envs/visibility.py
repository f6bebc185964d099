"""The region the landmark sensor actually sees from a pose: its field of view cut by the walls and the world.

The sensor reads a landmark when the line of sight from the robot's centre misses every wall capsule
(``ekfslam_gym.sim.sensor``). Casting rays with the same capsule test (``compiled.cast_rays``, the wall scan's
kernel) across the field of view gives, per ray, the distance to the first wall surface: the star-shaped
visibility polygon around the robot. The sensor's ``min_range`` (0.2 m by default, inside the robot's body in the
picture) is left out. The renderer shades it; nothing here runs in the env's step.
"""

from __future__ import annotations

import math

import numpy as np

from .. import compiled

RAY_SPACING = math.radians(0.5)  # [rad] between rays: under a pixel at 6 m on a 640 px frame of a 20 m world


def visibility_polygon(
    pose: np.ndarray,
    walls: np.ndarray,
    wall_radius: float,
    max_range: float,
    fov: float,
    bounds: np.ndarray | None = None,
    spacing: float = RAY_SPACING,
) -> np.ndarray:
    """Vertices (k, 2) in m of the region a sensor at ``pose`` (x, y, theta) can see, in order along the arc.

    A field of view under 2 pi starts and ends at the robot's centre (a wedge); all round, the polygon is the
    ring of ray ends. Between two rays the polygon keeps to the nearer of their two distances, so it never
    reaches past a wall's end that falls between them. ``bounds`` (xmin, ymin, xmax, ymax) clips the rays at
    the world's edge as well.
    """
    x, y, theta = (float(v) for v in np.asarray(pose, dtype=float).reshape(3))
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(theta)):
        raise ValueError(f"pose must be finite (x, y, theta), got {pose!r}")
    if not (max_range > 0 and math.isfinite(fov) and 0 < fov <= 2 * math.pi):
        raise ValueError(f"max_range must be > 0 and fov in (0, 2 pi], got {max_range!r}, {fov!r}")
    full = fov >= 2 * math.pi - 1e-9
    n = max(2, int(math.ceil(fov / spacing)) + (0 if full else 1))
    angles = np.linspace(-0.5 * fov, 0.5 * fov, n, endpoint=not full)
    reach = np.empty(n)
    walls = np.ascontiguousarray(walls, dtype=np.float64).reshape(-1, 4)
    compiled.cast_rays(x, y, theta, angles, walls, float(wall_radius), float(max_range), reach)
    heading = theta + angles
    direction = np.stack([np.cos(heading), np.sin(heading)], axis=1)
    if bounds is not None:
        reach = np.minimum(reach, _to_box(np.array([x, y]), direction, np.asarray(bounds, dtype=float)))
    # Each ray i contributes its end; where the next ray reaches further (or less far), the step between them
    # is taken at the nearer distance on both rays, so the chord never cuts behind a wall's end.
    nxt = np.roll(reach, -1)
    near = np.minimum(reach, nxt)
    following = np.roll(direction, -1, axis=0)
    candidates = np.stack(
        [reach[:, None] * direction, near[:, None] * direction, near[:, None] * following], 1
    )
    keep = np.stack([np.ones(n, bool), reach > near, nxt > near], axis=1)
    if not full:
        keep[-1, 1:] = False  # a wedge ends at its last ray
    points = candidates[keep]  # row-major: each ray's end, then its steps towards the next ray
    ring = np.array([x, y]) + points
    return ring if full else np.vstack([[x, y], ring])


def _to_box(origin: np.ndarray, direction: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """Distance along each unit direction (n, 2) from ``origin`` inside the box to the box's edge."""
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(
            direction[:, 0] > 0,
            (bounds[2] - origin[0]) / direction[:, 0],
            np.where(direction[:, 0] < 0, (bounds[0] - origin[0]) / direction[:, 0], np.inf),
        )
        ty = np.where(
            direction[:, 1] > 0,
            (bounds[3] - origin[1]) / direction[:, 1],
            np.where(direction[:, 1] < 0, (bounds[1] - origin[1]) / direction[:, 1], np.inf),
        )
    return np.clip(np.minimum(tx, ty), 0.0, None)
