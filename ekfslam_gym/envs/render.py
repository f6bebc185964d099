"""The env's pygame picture of an EKF-SLAM belief, in the style of the course's figure.

Walls as capsules, true landmarks as black crosses, estimates of seen landmarks with their 3-sigma ellipses in
blue, the true robot in grey and black, the estimated robot with its 3-sigma position ellipse in red, the
step's readings as thin lines from the estimated robot, the region the sensor sees from the true pose shaded
faintly (its field of view cut by the walls and the world's edge, ``visibility.visibility_polygon``), trails of
both trajectories, and a legend that says which is which. A :class:`Scene` is everything that is drawn; the
renderer reads it and decides nothing. :class:`RenderOptions` are the reader's choices: the legend, and a
magnification of the landmark ellipses for large worlds, where 3 sigma is a few pixels.

pygame-ce is in the optional ``render`` extra, so it is imported only when a :class:`Renderer` is built.
``rgb_array`` draws on a plain ``pygame.Surface`` and never touches ``pygame.display``, so it runs headless.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..ellipses import SIGMAS, ellipse_points
from .visibility import visibility_polygon

__all__ = ["RENDER_MODES", "RenderOptions", "Scene", "Renderer", "ellipse_points"]

RENDER_MODES = ("rgb_array", "human")
# SDL's video drivers that draw nowhere: chosen by SDL_VIDEODRIVER, or SDL's fallback without a window system.
HEADLESS_DRIVERS = ("dummy", "offscreen")
ELLIPSE_POINTS = 24
ARC_POINTS = 32  # points on the field-of-view arc
PAD = 8  # [px] around the world
TEXT_BAND = 20  # [px] at the top, kept whether or not there is text so the map never shifts
LEGEND_ROW = 18  # [px] per row of the legend band at the bottom
LEGEND_MARK = 21  # [px] from an entry's left edge to its label
LEGEND_GAP = 12  # [px] between a label and the next column
PX_LIMIT = 1.0e5  # [px] coordinates are clamped here so absurd estimates cannot overflow pygame's ints

BACKGROUND = (255, 255, 255)
BOUNDS = (215, 215, 215)
FOV_FILL = (255, 240, 230)
FOV_EDGE = (245, 205, 190)
WALL = (110, 110, 110)
TRUE = (0, 0, 0)
TRUE_BODY = (165, 165, 165)
TRUE_TRAIL = (120, 120, 120)
EST = (210, 30, 30)
EST_TRAIL = (235, 140, 140)
LANDMARK_EST = (30, 80, 220)
READING = (90, 90, 90)
TEXT = (20, 20, 20)


@dataclass(frozen=True)
class RenderOptions:
    """How a frame is drawn, not what: ``legend`` adds a band naming every mark; ``landmark_ellipse_scale``
    draws the landmark ellipses that many times larger (3 sigma x scale, said in the legend) so that they can
    be seen in a large world. Give them to ``gym.make(..., render_options={"legend": False})``."""

    legend: bool = True
    landmark_ellipse_scale: float = 1.0

    def __post_init__(self) -> None:
        if not isinstance(self.legend, bool):
            raise ValueError(f"RenderOptions.legend must be true or false, got {self.legend!r}")
        scale = self.landmark_ellipse_scale
        if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not (1.0 <= scale < math.inf):
            raise ValueError(f"RenderOptions.landmark_ellipse_scale must be a number >= 1, got {scale!r}")

    @classmethod
    def build(cls, options: RenderOptions | dict[str, Any] | None) -> RenderOptions:
        """``options`` as given to the env: None (the defaults), a mapping of the fields, or the options."""
        if options is None:
            return cls()
        if isinstance(options, cls):
            return options
        if not isinstance(options, dict):
            raise ValueError(f"render_options must be a mapping or RenderOptions, got {options!r}")
        unknown = sorted(set(options) - {"legend", "landmark_ellipse_scale"})
        if unknown:
            raise ValueError(f"render_options has no field {unknown}; valid: legend, landmark_ellipse_scale")
        return cls(**options)


@dataclass(frozen=True)
class Scene:
    """Everything one frame draws, in world coordinates (m, rad); built by the env from its state."""

    bounds: np.ndarray  # (4,) xmin, ymin, xmax, ymax in m
    walls: np.ndarray  # (k, 4) segments x1, y1, x2, y2 (m)
    wall_radius: float  # m
    robot_radius: float  # m
    landmarks_true: np.ndarray  # (n, 2)
    landmarks_est: np.ndarray  # (n, 2)
    landmark_covs: np.ndarray  # (n, 2, 2) marginal covariances
    seen: np.ndarray  # (n,) bool: draw estimates/ellipses only for these
    pose_true: np.ndarray  # (3,) x, y, theta
    pose_est: np.ndarray  # (3,)
    pose_cov: np.ndarray  # (3, 3)
    read_ids: np.ndarray  # (m,) int: landmarks read this step
    trail_true: np.ndarray  # (T, 2)
    trail_est: np.ndarray  # (T, 2)
    max_range: float
    fov: float  # rad, full field of view
    text: str = ""  # the header line; the env writes its own step count (env steps), log det and landmarks


class Renderer:
    """Draws :class:`Scene` frames for ``render_mode`` ``"rgb_array"`` (returns an image) or ``"human"``."""

    def __init__(
        self,
        render_mode: str,
        width: int = 640,
        height: int = 640,
        fps: int = 10,
        options: RenderOptions | dict[str, Any] | None = None,
    ) -> None:
        if render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode must be one of {list(RENDER_MODES)}, got {render_mode!r}")
        if width < 2 * PAD + 1 or height < 2 * PAD + TEXT_BAND + 1:
            raise ValueError(f"width and height are too small for a picture, got {width}x{height}")
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        try:
            import pygame
        except ImportError as error:  # the render extra is optional
            raise ImportError('rendering needs pygame-ce: pip install "ekfslam-gym[render]"') from error
        self._pg: Any = pygame
        self.options = RenderOptions.build(options)
        self.render_mode = render_mode
        self.width = int(width)
        self.height = int(height)
        self.fps = int(fps)
        self._surface = pygame.Surface((self.width, self.height))
        self._font: Any = None
        self._font_tried = False
        self._small_font: Any = None
        self._small_font_tried = False
        self._window: Any = None
        self._clock: Any = None
        self._scale, self._ox, self._oy = 1.0, 0.0, 0.0  # set from the scene's bounds on every frame
        self._legend_columns: list[int] = []  # the x of each column, set with the legend's layout
        self._legend_band = self._legend_layout() * LEGEND_ROW + 4 if self.options.legend else 0
        if self.height - 2 * PAD - TEXT_BAND - self._legend_band < 1:
            raise ValueError(
                f"height {height} leaves no room for the map under the legend; make the frame taller or pass "
                "render_options={'legend': False}"
            )

    # -- geometry ------------------------------------------------------------------------------------------

    def _transform(self, bounds: np.ndarray) -> tuple[float, float, float]:
        """Scale (px/m) and the pixel position of world (0, 0), keeping aspect ratio, centred, y up."""
        b = np.asarray(bounds, dtype=float).reshape(-1)
        if b.shape != (4,) or not np.isfinite(b).all() or b[2] <= b[0] or b[3] <= b[1]:
            raise ValueError(f"bounds must be finite (xmin, ymin, xmax, ymax) with max > min, got {bounds!r}")
        avail_w = self.width - 2 * PAD
        avail_h = self.height - 2 * PAD - TEXT_BAND - self._legend_band
        scale = min(avail_w / (b[2] - b[0]), avail_h / (b[3] - b[1]))
        left = PAD + 0.5 * (avail_w - scale * (b[2] - b[0]))
        bottom = self.height - PAD - self._legend_band - 0.5 * (avail_h - scale * (b[3] - b[1]))
        return float(scale), float(left - scale * b[0]), float(bottom + scale * b[1])

    def _px(self, xy: np.ndarray) -> np.ndarray:
        """World points (..., 2) in m to pixel coordinates (..., 2), clamped to a sane range."""
        xy = np.asarray(xy, dtype=float)
        out = np.empty_like(xy)
        out[..., 0] = self._ox + self._scale * xy[..., 0]
        out[..., 1] = self._oy - self._scale * xy[..., 1]
        return np.clip(out, -PX_LIMIT, PX_LIMIT)

    def world_to_pixels(self, bounds: np.ndarray, xy: np.ndarray) -> np.ndarray:
        """Pixel (column, row) of world points (..., 2) in m for a scene with these ``bounds``, for overlays."""
        self._scale, self._ox, self._oy = self._transform(bounds)
        return self._px(xy)

    # -- drawing -------------------------------------------------------------------------------------------

    def render(self, scene: Scene) -> np.ndarray | None:
        """Draw ``scene``; ``rgb_array`` returns an (height, width, 3) uint8 image, ``human`` shows it."""
        self._draw(scene)
        if self.render_mode == "rgb_array":
            # Row-major RGB bytes are already (H, W, 3): 10x cheaper than surfarray.array3d + transpose,
            # and a bytearray keeps the returned frame writable like any other numpy array.
            data = bytearray(self._pg.image.tobytes(self._surface, "RGB"))
            return np.frombuffer(data, dtype=np.uint8).reshape(self.height, self.width, 3)
        self._show()
        return None

    def _draw(self, scene: Scene) -> None:
        pg = self._pg
        surf = self._surface
        self._scale, self._ox, self._oy = self._transform(scene.bounds)
        surf.fill(BACKGROUND)
        b = np.asarray(scene.bounds, dtype=float)
        corners = self._px(np.array([[b[0], b[3]], [b[2], b[1]]]))
        pg.draw.rect(surf, BOUNDS, pg.Rect(*corners[0], *(corners[1] - corners[0])), width=1)

        pose_est = np.asarray(scene.pose_est, dtype=float)
        pose_true = np.asarray(scene.pose_true, dtype=float)
        est_ok = pose_est.shape == (3,) and bool(np.isfinite(pose_est).all())
        true_ok = pose_true.shape == (3,) and bool(np.isfinite(pose_true).all())

        walls = np.asarray(scene.walls, dtype=float).reshape(-1, 4)
        walls = walls[np.isfinite(walls).all(axis=1)]
        if true_ok:
            self._draw_fov(
                pose_true, walls, float(scene.wall_radius), float(scene.max_range), float(scene.fov), b
            )
        self._draw_walls(walls, float(scene.wall_radius))
        self._draw_trail(scene.trail_true, TRUE_TRAIL)
        self._draw_trail(scene.trail_est, EST_TRAIL)

        landmarks_est = np.asarray(scene.landmarks_est, dtype=float).reshape(-1, 2)
        seen = np.asarray(scene.seen, dtype=bool).reshape(-1)
        if est_ok:
            self._draw_readings(pose_est, landmarks_est, np.asarray(scene.read_ids).reshape(-1))
        self._draw_landmarks_true(np.asarray(scene.landmarks_true, dtype=float).reshape(-1, 2))
        self._draw_landmarks_est(landmarks_est, np.asarray(scene.landmark_covs, dtype=float), seen)

        radius = max(5.0, self._scale * float(scene.robot_radius))  # [px] seen even in a large world
        if true_ok:
            centre = self._px(pose_true[:2])
            pg.draw.circle(surf, TRUE_BODY, centre, radius)
            pg.draw.circle(surf, TRUE, centre, radius, width=1)
            self._heading(pose_true, radius, TRUE)
        if est_ok:
            centre = self._px(pose_est[:2])
            pg.draw.circle(surf, EST, centre, radius, width=2)
            self._heading(pose_est, radius, EST)
            pose_cov = np.asarray(scene.pose_cov, dtype=float)
            if pose_cov.shape == (3, 3):  # on top of both robots, two pixels wide: it is the picture's point
                points, valid = ellipse_points(pose_est[:2], pose_cov[:2, :2])
                if valid[0]:
                    pg.draw.lines(surf, EST, True, self._px(points[0]).tolist(), 2)

        if scene.text:
            self._draw_text(str(scene.text))
        if self.options.legend:
            self._draw_legend()

    def _draw_fov(
        self,
        pose: np.ndarray,
        walls: np.ndarray,
        wall_radius: float,
        max_range: float,
        fov: float,
        bounds: np.ndarray,
    ) -> None:
        """The region the sensor sees from the true pose: its field of view, cut by the walls (the sensor's
        own line-of-sight test) and by the world's edge."""
        if not (max_range > 0 and math.isfinite(max_range) and math.isfinite(fov) and fov > 0):
            return  # also rejects NaN; an infinite range is cut by the world's edge below
        reach = min(max_range, float(np.hypot(bounds[2] - bounds[0], bounds[3] - bounds[1])))
        polygon = visibility_polygon(pose, walls, wall_radius, reach, min(fov, 2 * math.pi), bounds)
        points = self._px(polygon).tolist()
        self._pg.draw.polygon(self._surface, FOV_FILL, points)
        self._pg.draw.lines(self._surface, FOV_EDGE, True, points)

    def _draw_walls(self, walls: np.ndarray, wall_radius: float) -> None:
        """Capsules: a quad per segment plus round caps, so corners meet like the collision shapes."""
        walls = walls[np.isfinite(walls).all(axis=1)]
        if len(walls) == 0:
            return
        pg = self._pg
        surf = self._surface
        ends = self._px(walls.reshape(-1, 2, 2))  # (k, 2, 2) px
        r_px = self._scale * wall_radius if math.isfinite(wall_radius) else 0.0
        if r_px < 1.0:
            for a, b in ends.tolist():
                pg.draw.line(surf, WALL, a, b, 2)
            return
        d = ends[:, 1] - ends[:, 0]
        length = np.hypot(d[:, 0], d[:, 1])
        normal = np.zeros_like(d)
        long = length > 1e-9
        normal[long] = np.stack([-d[long, 1], d[long, 0]], axis=1) / length[long, None] * r_px
        quads = np.stack(
            [ends[:, 0] + normal, ends[:, 1] + normal, ends[:, 1] - normal, ends[:, 0] - normal], axis=1
        )
        for quad, (a, b), is_long in zip(quads.tolist(), ends.tolist(), long.tolist()):
            if is_long:
                pg.draw.polygon(surf, WALL, quad)
            pg.draw.circle(surf, WALL, a, r_px)
            pg.draw.circle(surf, WALL, b, r_px)

    def _draw_trail(self, trail: np.ndarray, color: tuple[int, int, int]) -> None:
        trail = np.asarray(trail, dtype=float).reshape(-1, 2)
        trail = trail[np.isfinite(trail).all(axis=1)]
        if len(trail) >= 2:
            self._pg.draw.aalines(self._surface, color, False, self._px(trail).tolist())

    def _draw_readings(self, pose: np.ndarray, landmarks_est: np.ndarray, read_ids: np.ndarray) -> None:
        """Thin lines to the estimates of the landmarks read this step (ids out of range are ignored)."""
        if read_ids.size == 0 or len(landmarks_est) == 0:
            return
        ids = read_ids.astype(np.int64, copy=False)
        ids = ids[(ids >= 0) & (ids < len(landmarks_est))]
        targets = landmarks_est[ids]
        targets = targets[np.isfinite(targets).all(axis=1)]
        if len(targets) == 0:
            return
        start = self._px(pose[:2]).tolist()
        for end in self._px(targets).tolist():
            self._pg.draw.aaline(self._surface, READING, start, end)

    def _draw_landmarks_true(self, landmarks: np.ndarray) -> None:
        landmarks = landmarks[np.isfinite(landmarks).all(axis=1)]
        pg = self._pg
        s = 4
        for x, y in self._px(landmarks).tolist():
            pg.draw.line(self._surface, TRUE, (x - s, y - s), (x + s, y + s), 2)
            pg.draw.line(self._surface, TRUE, (x - s, y + s), (x + s, y - s), 2)

    def _draw_landmarks_est(self, landmarks: np.ndarray, covs: np.ndarray, seen: np.ndarray) -> None:
        """Seen estimates only: an unseen landmark's estimate and covariance are placeholders."""
        n = min(len(landmarks), len(seen), len(covs))
        if n == 0:
            return
        mask = seen[:n]
        if not mask.any():
            return
        centres = landmarks[:n][mask]
        points, valid = ellipse_points(centres, covs[:n][mask], SIGMAS * self.options.landmark_ellipse_scale)
        pg = self._pg
        surf = self._surface
        for poly in self._px(points[valid]).tolist():
            pg.draw.aalines(surf, LANDMARK_EST, True, poly)
        centres = centres[np.isfinite(centres).all(axis=1)]
        for c in self._px(centres).tolist():
            pg.draw.circle(surf, LANDMARK_EST, c, 3)

    def _heading(self, pose: np.ndarray, radius: float, color: tuple[int, int, int]) -> None:
        start = self._px(pose[:2])
        tip = start + 1.8 * radius * np.array([math.cos(pose[2]), -math.sin(pose[2])])
        self._pg.draw.line(self._surface, color, start.tolist(), tip.tolist(), 2)

    def _draw_text(self, text: str) -> None:
        """The text line is a convenience: without a usable font module the frame is drawn without it."""
        if not self._font_tried:
            self._font_tried = True
            try:
                self._pg.font.init()
                self._font = self._pg.font.Font(None, 20)
            except Exception:  # a missing font must not break rendering
                self._font = None
        if self._font is not None:
            self._surface.blit(self._font.render(text, True, TEXT), (PAD, 3))

    def _legend_entries(self) -> list[tuple[str, str, tuple[int, int, int]]]:
        """(mark, label, colour) for every kind of mark the frame draws."""
        scale = self.options.landmark_ellipse_scale
        sigma = f"{SIGMAS:g}\u03c3" + (f" \u00d7{scale:g}" if scale != 1.0 else "")
        return [
            ("disc", "true robot", TRUE_BODY),
            ("ring", f"estimated robot, {SIGMAS:g}\u03c3", EST),
            ("cross", "true landmark", TRUE),
            ("dot", f"landmark estimate, {sigma}", LANDMARK_EST),
            ("line", "true path", TRUE_TRAIL),
            ("line", "estimated path", EST_TRAIL),
            ("line", "reading this step", READING),
            ("area", "what the sensor sees", FOV_EDGE),
        ]

    def _legend_layout(self) -> int:
        """Lay the entries out in as many columns as fit the frame, each as wide as its longest label; the
        number of rows."""
        entries = self._legend_entries()
        font = self._legend_font()
        widths = [font.size(label)[0] if font is not None else 8 * len(label) for _, label, _ in entries]
        for columns in range(len(entries), 0, -1):
            column_widths = [
                max(widths[i] for i in range(c, len(entries), columns)) + LEGEND_MARK + LEGEND_GAP
                for c in range(columns)
            ]
            if sum(column_widths) - LEGEND_GAP <= self.width - 2 * PAD or columns == 1:
                self._legend_columns = [PAD + sum(column_widths[:c]) for c in range(columns)]
                return -(-len(entries) // columns)
        return len(entries)  # unreachable: one column always fits the loop's last test

    def _draw_legend(self) -> None:
        """The legend band under the map: a sample of each mark and what it is."""
        pg = self._pg
        surf = self._surface
        font = self._legend_font()
        columns = self._legend_columns
        top = self.height - self._legend_band + 2
        pg.draw.line(surf, BOUNDS, (PAD, top - 2), (self.width - PAD, top - 2))
        for i, (mark, label, colour) in enumerate(self._legend_entries()):
            x = columns[i % len(columns)]
            y = top + (i // len(columns)) * LEGEND_ROW + LEGEND_ROW // 2
            if mark == "disc":
                pg.draw.circle(surf, TRUE_BODY, (x + 8, y), 6)
                pg.draw.circle(surf, TRUE, (x + 8, y), 6, width=1)
            elif mark == "ring":
                pg.draw.circle(surf, EST, (x + 8, y), 6, width=2)
            elif mark == "cross":
                pg.draw.line(surf, TRUE, (x + 4, y - 4), (x + 12, y + 4), 2)
                pg.draw.line(surf, TRUE, (x + 4, y + 4), (x + 12, y - 4), 2)
            elif mark == "dot":
                pg.draw.circle(surf, colour, (x + 8, y), 3)
                pg.draw.ellipse(surf, colour, pg.Rect(x, y - 5, 16, 10), width=1)
            elif mark == "area":
                pg.draw.rect(surf, FOV_FILL, pg.Rect(x, y - 5, 16, 10))
                pg.draw.rect(surf, colour, pg.Rect(x, y - 5, 16, 10), width=1)
            else:
                pg.draw.line(surf, colour, (x, y), (x + 16, y), 2)
            if font is not None:
                text = font.render(label, True, TEXT)
                surf.blit(text, (x + LEGEND_MARK, y - text.get_height() // 2))

    def _legend_font(self) -> Any:
        if not self._small_font_tried:
            self._small_font_tried = True
            try:
                self._pg.font.init()
                self._small_font = self._pg.font.Font(None, 18)
            except Exception:  # a missing font must not break rendering: the marks are still drawn
                self._small_font = None
        return self._small_font

    # -- window --------------------------------------------------------------------------------------------

    def _show(self) -> None:
        pg = self._pg
        if self._window is None:
            try:
                pg.display.init()
            except pg.error as error:
                raise RuntimeError(
                    f"render_mode='human' needs a display and SDL could not open one ({error}; "
                    f"{_display_variables()}); use render_mode='rgb_array' for frames"
                ) from None
            driver = pg.display.get_driver()
            if driver in HEADLESS_DRIVERS:
                warnings.warn(
                    f"render_mode='human' shows nothing: SDL's video driver is {driver!r}, which has no "
                    f"screen ({_display_variables()}); render() returns None, as human mode does. Use "
                    "render_mode='rgb_array' for frames",
                    stacklevel=4,
                )
            pg.display.set_caption("ekfslam-gym")
            self._window = pg.display.set_mode((self.width, self.height))
            self._clock = pg.time.Clock()
        pg.event.pump()
        self._window.blit(self._surface, (0, 0))
        pg.display.flip()
        self._clock.tick(self.fps)

    def close(self) -> None:
        """Close the window if one was opened; safe to call more than once and in ``rgb_array`` mode."""
        if self._window is not None:
            self._pg.display.quit()
            self._window = None
            self._clock = None


def _display_variables() -> str:
    """What the environment says about a display, for the messages above."""
    names = ("SDL_VIDEODRIVER", "DISPLAY", "WAYLAND_DISPLAY")
    set_ = [f"{name}={os.environ[name]!r}" for name in names if os.environ.get(name)]
    unset = [name for name in names[1:] if not os.environ.get(name)]
    parts = set_ + ([f"{' and '.join(unset)} unset"] if unset else [])
    return ", ".join(parts)
