"""The range-bearing landmark sensor and the coarse wall scan.

Landmarks are points with known correspondences; a reading is (range m, bearing rad) in the robot frame, with
independent Gaussian noise of constant standard deviation (so its covariance Q is a constant diag), bearing
wrapped to (-pi, pi]. A landmark is read when its range is in [min_range, max_range], its bearing within half the
field of view, and the line of sight from the robot's centre misses every wall capsule; optionally only with
probability ``detection_prob``, and with false readings (clutter, id -1) added: a Poisson number with mean
``clutter_rate``, uniform in range and bearing over the field of view (the usual clutter model: a constant
density in reading space). The scan gives the
distance from the robot's centre to the nearest wall surface along a few beams, noise-free and clipped, because
the belief holds no walls and a policy must still avoid them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .. import compiled


@dataclass(frozen=True)
class SensorParams:
    """Sensor configuration.

    min_range, max_range: m. fov: full field of view, rad (2 pi for all round), centred on the heading.
    range_std: m; bearing_std: rad. n_beams: wall-scan beams, evenly spaced over 360 degrees starting at the
    heading. scan_max_range: m, where the scan clips. detection_prob: probability that a visible landmark is
    read. clutter_rate: expected false readings per step. The defaults (1, 0) draw no extra random numbers.
    """

    min_range: float = 0.2
    max_range: float = 6.0
    fov: float = math.pi
    range_std: float = 0.05
    bearing_std: float = math.radians(1.0)
    n_beams: int = 16
    scan_max_range: float = 5.0
    detection_prob: float = 1.0
    clutter_rate: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.min_range) and self.min_range >= 0.0):
            raise ValueError(f"SensorParams.min_range must be finite and >= 0, got {self.min_range!r}")
        if not (math.isfinite(self.max_range) and self.max_range > self.min_range):
            raise ValueError(f"SensorParams.max_range must be finite and > min_range, got {self.max_range!r}")
        if not (0.0 < self.fov <= 2.0 * math.pi):
            raise ValueError(f"SensorParams.fov must be in (0, 2 pi] rad, got {self.fov!r}")
        for name in ("range_std", "bearing_std"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"SensorParams.{name} must be finite and > 0, got {value!r}")
        if isinstance(self.n_beams, bool) or not isinstance(self.n_beams, int) or self.n_beams < 1:
            raise ValueError(f"SensorParams.n_beams must be an int >= 1, got {self.n_beams!r}")
        if not (math.isfinite(self.scan_max_range) and self.scan_max_range > 0.0):
            raise ValueError(
                f"SensorParams.scan_max_range must be finite and > 0, got {self.scan_max_range!r}"
            )

        if not (isinstance(self.detection_prob, (int, float)) and 0.0 < self.detection_prob <= 1.0):
            raise ValueError(f"SensorParams.detection_prob must be in (0, 1], got {self.detection_prob!r}")
        if not (
            isinstance(self.clutter_rate, (int, float))
            and math.isfinite(self.clutter_rate)
            and self.clutter_rate >= 0.0
        ):
            raise ValueError(f"SensorParams.clutter_rate must be finite and >= 0, got {self.clutter_rate!r}")

    @property
    def cov(self) -> np.ndarray:
        """Covariance Q (2, 2) of one reading's noise: diag(range_std^2, bearing_std^2)."""
        return np.diag([self.range_std**2, self.bearing_std**2])


class Readings(NamedTuple):
    """Landmark readings of one step, ordered by id, clutter (id -1) last.

    ids: (m,) int64, 0-based landmark indices, -1 for a false reading; z: (m, 2) float64, (range m, bearing rad in (-pi, pi]).
    """

    ids: np.ndarray
    z: np.ndarray


class RangeBearingSensor:
    """Reads landmarks and scans walls from a pose; knows the map, nothing of the robot or the filter."""

    def __init__(
        self, landmarks: np.ndarray, walls: np.ndarray, wall_radius: float, params: SensorParams | None = None
    ) -> None:
        self.params = params if params is not None else SensorParams()
        self.landmarks = np.ascontiguousarray(landmarks, dtype=np.float64).reshape(-1, 2)
        self.walls = np.ascontiguousarray(walls, dtype=np.float64).reshape(-1, 4)
        self.wall_radius = float(wall_radius)
        p = self.params
        self._half_fov = 0.5 * p.fov
        # Reads every visible landmark and nothing else: then ``sense`` draws only the (m, 2) normals.
        self.ideal = p.detection_prob >= 1.0 and p.clutter_rate <= 0.0
        self.beam_angles = np.arange(p.n_beams) * (2.0 * math.pi / p.n_beams)
        # scratch buffers: the kernel writes the m visible readings here and sense() copies them out
        self._ids = np.empty(self.landmarks.shape[0], dtype=np.int64)
        self._z = np.empty((self.landmarks.shape[0], 2))

    def true_readings(self, pose: tuple[float, float, float]) -> Readings:
        """Noise-free readings from pose (x m, y m, theta rad): what the sensor would see exactly."""
        p = self.params
        m = compiled.visible_landmarks(
            pose[0], pose[1], pose[2], self.landmarks, self.walls, self.wall_radius,
            p.min_range, p.max_range, self._half_fov, self._ids, self._z,
        )  # fmt: skip
        return Readings(self._ids[:m].copy(), self._z[:m].copy())

    def sense(self, pose: tuple[float, float, float], rng: np.random.Generator) -> Readings:
        """Noisy readings from pose (x m, y m, theta rad), drawn from ``rng``: with ``detection_prob`` < 1 first
        one uniform per visible landmark (kept if below it), then (m, 2) normals in id order, then with
        ``clutter_rate`` > 0 a Poisson count and its ranges and bearings."""
        ids, z = self.true_readings(pose)
        p = self.params
        if p.detection_prob < 1.0 and z.shape[0]:
            keep = rng.random(z.shape[0]) < p.detection_prob
            ids, z = ids[keep], z[keep]
        if z.shape[0]:
            compiled.add_reading_noise(z, rng.standard_normal(z.shape), p.range_std, p.bearing_std)
        if p.clutter_rate > 0.0:
            count = int(rng.poisson(p.clutter_rate))
            if count:
                clutter = np.empty((count, 2))
                clutter[:, 0] = rng.uniform(p.min_range, p.max_range, count)
                clutter[:, 1] = rng.uniform(-self._half_fov, self._half_fov, count)
                ids = np.concatenate([ids, np.full(count, -1, dtype=np.int64)])
                z = np.concatenate([z, clutter])
        return Readings(ids, z)

    def scan(self, pose: tuple[float, float, float]) -> np.ndarray:
        """Wall distances (n_beams,) float64 in m from the robot's centre, clipped at scan_max_range.

        Beam i points at heading + 2 pi i / n_beams (counter-clockwise, beam 0 straight ahead).
        """
        out = np.empty(self.beam_angles.shape[0])
        compiled.cast_rays(
            pose[0], pose[1], pose[2], self.beam_angles, self.walls, self.wall_radius,
            self.params.scan_max_range, out,
        )  # fmt: skip
        return out
