"""The pygame renderer: headless frames that show what the scene says, and nothing for what it does not."""

from __future__ import annotations

import dataclasses
import sys
import time
import warnings

import gymnasium as gym
import numpy as np
import pytest

pygame = pytest.importorskip("pygame")

from ekfslam_gym.envs import render  # noqa: E402
from ekfslam_gym.envs.render import Renderer, Scene, ellipse_points  # noqa: E402

W, H = 160, 120


def make_scene(**overrides: object) -> Scene:
    """A 10 m x 8 m box, three landmarks (the first two seen), the robot at (3, 3) facing +x."""
    fields: dict[str, object] = dict(
        bounds=np.array([0.0, 0.0, 10.0, 8.0]),
        walls=np.array([[0, 0, 10, 0], [10, 0, 10, 8], [10, 8, 0, 8], [0, 8, 0, 0], [5, 0, 5, 3]], float),
        wall_radius=0.1,
        robot_radius=0.3,
        landmarks_true=np.array([[7.0, 5.0], [2.0, 6.0], [8.0, 2.0]]),
        landmarks_est=np.array([[7.2, 5.1], [2.1, 5.8], [8.0, 2.0]]),
        landmark_covs=np.array([np.diag([0.04, 0.02]), np.diag([0.03, 0.05]), np.diag([0.04, 0.04])]),
        seen=np.array([True, True, False]),
        pose_true=np.array([3.0, 3.0, 0.0]),
        pose_est=np.array([3.1, 2.9, 0.05]),
        pose_cov=np.diag([0.02, 0.02, 0.01]),
        read_ids=np.array([0]),
        trail_true=np.array([[1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]),
        trail_est=np.array([[1.0, 1.0], [2.1, 1.9], [3.1, 2.9]]),
        max_range=4.0,
        fov=np.pi / 2,
        text="step 3  log det -12.0  reward 0.1",
    )
    fields.update(overrides)
    return Scene(**fields)  # type: ignore[arg-type]


@pytest.fixture
def renderer():
    r = Renderer("rgb_array", width=W, height=H, options={"legend": False})
    yield r
    r.close()


def blue_pixels(frame: np.ndarray) -> np.ndarray:
    """Mask of the landmark-estimate blue: nothing else in the picture is strongly blue."""
    rgb = frame.astype(int)
    return (rgb[..., 2] > 150) & (rgb[..., 2] - rgb[..., 0] > 80) & (rgb[..., 2] - rgb[..., 1] > 50)


def region(frame: np.ndarray, centre: np.ndarray, half: int) -> np.ndarray:
    col, row = np.round(centre).astype(int)
    return frame[max(row - half, 0) : row + half + 1, max(col - half, 0) : col + half + 1]


def test_rgb_array_frame_is_a_picture(renderer: Renderer) -> None:
    frame = renderer.render(make_scene())
    assert isinstance(frame, np.ndarray)
    assert frame.shape == (H, W, 3) and frame.dtype == np.uint8
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) >= 6  # background, walls, blue, red, grey, black...
    background = np.array(render.BACKGROUND)
    centre = renderer.world_to_pixels(np.array([0.0, 0.0, 10.0, 8.0]), np.array([3.0, 3.0]))
    col, row = np.round(centre).astype(int)
    assert not np.array_equal(frame[row, col], background)  # the robot sits there
    assert (region(frame, centre, 1) != background).any(axis=-1).all()  # a disc, not a dot
    assert frame.flags.writeable  # callers may draw on the frame


def test_world_maps_to_pixels_keeping_aspect_and_y_up(renderer: Renderer) -> None:
    bounds = np.array([0.0, 0.0, 20.0, 5.0])  # wider than the canvas: x decides the scale
    px = renderer.world_to_pixels(bounds, np.array([[0.0, 0.0], [20.0, 0.0], [0.0, 5.0], [10.0, 2.5]]))
    assert px[1, 0] - px[0, 0] == pytest.approx(4 * (px[0, 1] - px[2, 1]))  # same px per metre in x and y
    assert px[2, 1] < px[0, 1]  # y up
    assert 0 <= px[:, 0].min() and px[:, 0].max() <= W and 0 <= px[:, 1].min() and px[:, 1].max() <= H
    assert px[3, 0] == pytest.approx(W / 2)
    tall = np.array([0.0, 0.0, 5.0, 20.0])  # taller than the canvas: y decides the scale
    px = renderer.world_to_pixels(tall, np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 20.0]]))
    assert 4 * (px[1, 0] - px[0, 0]) == pytest.approx(px[0, 1] - px[2, 1])
    assert 0 <= px[:, 1].min() and px[:, 1].max() <= H


def test_both_robots_are_drawn_where_they_are(renderer: Renderer) -> None:
    bounds = np.array([0.0, 0.0, 10.0, 8.0])
    apart = make_scene(pose_est=np.array([7.5, 6.5, 0.0]), read_ids=np.array([], int))
    frame = renderer.render(apart)
    background = np.array(render.BACKGROUND)
    true_centre, est_centre = renderer.world_to_pixels(bounds, np.array([[3.0, 3.0], [7.5, 6.5]]))
    assert (region(frame, true_centre, 1) != background).any(axis=-1).all()  # a filled disc
    assert (region(frame, est_centre, 2) != background).any(axis=-1).sum() >= 8  # a ring and its heading


def test_pixels_follow_the_pose(renderer: Renderer) -> None:
    before = renderer.render(make_scene())
    after = renderer.render(
        make_scene(pose_true=np.array([7.0, 1.5, 1.0]), pose_est=np.array([7.1, 1.6, 1.0]))
    )
    assert not np.array_equal(before, after)
    moved_to = renderer.world_to_pixels(np.array([0.0, 0.0, 10.0, 8.0]), np.array([7.0, 1.5]))
    assert not np.array_equal(region(before, moved_to, 2), region(after, moved_to, 2))


def test_unseen_landmarks_get_no_estimate_or_ellipse(renderer: Renderer) -> None:
    none_seen = renderer.render(make_scene(seen=np.zeros(3, bool), read_ids=np.array([], int)))
    some_seen = renderer.render(make_scene(read_ids=np.array([], int)))
    assert blue_pixels(none_seen).sum() == 0
    assert blue_pixels(some_seen).sum() > 20
    # the third landmark is unseen in both: seeing it adds blue around its estimate only
    all_seen = renderer.render(make_scene(seen=np.ones(3, bool), read_ids=np.array([], int)))
    third = renderer.world_to_pixels(np.array([0.0, 0.0, 10.0, 8.0]), np.array([8.0, 2.0]))
    assert blue_pixels(region(some_seen, third, 10)).sum() == 0
    assert blue_pixels(region(all_seen, third, 10)).sum() > 5


def test_readings_draw_lines_and_ignore_bad_ids(renderer: Renderer) -> None:
    quiet = renderer.render(make_scene(read_ids=np.array([], int)))
    reading = renderer.render(make_scene(read_ids=np.array([0, 1])))
    bad_ids = renderer.render(make_scene(read_ids=np.array([-1, 3, 99])))
    assert not np.array_equal(quiet, reading)
    np.testing.assert_array_equal(quiet, bad_ids)


def test_ellipse_points_lie_on_the_three_sigma_contour() -> None:
    cov = np.array([[0.5, 0.2], [0.2, 0.3]])
    centre = np.array([1.0, -2.0])
    points, valid = ellipse_points(centre, cov)
    assert valid.tolist() == [True] and points.shape == (1, render.ELLIPSE_POINTS, 2)
    d = points[0] - centre
    mahalanobis = np.sqrt(np.einsum("ni,ij,nj->n", d, np.linalg.inv(cov), d))
    np.testing.assert_allclose(mahalanobis, 3.0, rtol=1e-9)


def test_degenerate_covariances_are_skipped_without_crashing(renderer: Renderer) -> None:
    covs = np.array(
        [
            np.zeros((2, 2)),
            np.full((2, 2), np.nan),
            np.array([[np.inf, 0.0], [0.0, 1.0]]),
            -np.eye(2),
            np.array([[1.0, 1.0], [1.0, 1.0]]),  # rank one: a segment, still drawable
            1e12 * np.eye(2),  # a prior: enormous, must not overflow pixel coordinates
        ]
    )
    _, valid = ellipse_points(np.zeros((6, 2)), covs)
    assert valid.tolist() == [False, False, False, False, True, True]
    n = len(covs)
    scene = make_scene(
        landmarks_true=np.zeros((n, 2)) + 5.0,
        landmarks_est=np.vstack([[5.0, 5.0]] * (n - 1) + [[np.nan, 1.0]]),
        landmark_covs=covs,
        seen=np.ones(n, bool),
        read_ids=np.arange(n),
        pose_cov=np.full((3, 3), np.nan),
    )
    frame = renderer.render(scene)
    assert frame.shape == (H, W, 3)
    for bad in (np.zeros((3, 3)), -np.eye(3), np.full((3, 3), np.inf)):
        assert renderer.render(make_scene(pose_cov=bad)).shape == (H, W, 3)


def test_empty_and_non_finite_inputs_still_draw(renderer: Renderer) -> None:
    empty = make_scene(
        walls=np.zeros((0, 4)),
        landmarks_true=np.zeros((0, 2)),
        landmarks_est=np.zeros((0, 2)),
        landmark_covs=np.zeros((0, 2, 2)),
        seen=np.zeros(0, bool),
        read_ids=np.zeros(0, int),
        trail_true=np.zeros((0, 2)),
        trail_est=np.zeros((1, 2)),
        max_range=np.inf,
        fov=2 * np.pi,
        text="",
    )
    frame = renderer.render(empty)
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 2  # the robots are still there
    lost = renderer.render(make_scene(pose_est=np.array([np.nan, 0.0, 0.0])))
    assert lost.shape == (H, W, 3)


def test_absurd_sizes_stay_fast_and_in_place(renderer: Renderer) -> None:
    """Huge pixel coordinates make pygame's fills take seconds (and leak past int32); they must be clamped."""
    start = time.perf_counter()
    frame = renderer.render(make_scene(max_range=1e6, read_ids=np.array([], int)))  # ~1 s if not capped
    assert time.perf_counter() - start < 0.25
    behind = renderer.world_to_pixels(np.array([0.0, 0.0, 10.0, 8.0]), np.array([1.0, 5.0]))
    np.testing.assert_array_equal(region(frame, behind, 2), np.broadcast_to(render.BACKGROUND, (5, 5, 3)))


def test_a_diverged_estimate_draws_fast(renderer: Renderer) -> None:
    far = 1e7  # [m] a filter that has run away: ~1e8 px from the canvas
    scene = make_scene(
        pose_est=np.array([far, -far, 0.0]),
        landmarks_est=np.array([[far, far], [2.1, 5.8], [8.0, 2.0]]),
        read_ids=np.array([0, 1]),
        trail_est=np.array([[1.0, 1.0], [far, -far]]),
        walls=np.array([[0.0, 0.0, far, far]]),
    )
    start = time.perf_counter()
    frame = renderer.render(scene)
    assert time.perf_counter() - start < 0.25
    assert frame.shape == (H, W, 3)


def test_bad_bounds_raise(renderer: Renderer) -> None:
    with pytest.raises(ValueError, match="bounds"):
        renderer.render(make_scene(bounds=np.array([0.0, 0.0, 0.0, 8.0])))


def test_rgb_array_never_opens_the_display() -> None:
    pygame.display.quit()
    r = Renderer("rgb_array", width=W, height=H, options={"legend": False})
    r.render(make_scene())
    r.close()
    assert not pygame.display.get_init()


def test_human_mode_runs_headless(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    r = Renderer("human", width=W, height=H, fps=1000, options={"legend": False})
    try:
        with pytest.warns(UserWarning, match="shows nothing: SDL's video driver is 'dummy'"):
            assert r.render(make_scene()) is None
        assert pygame.display.get_init() and pygame.display.get_surface().get_size() == (W, H)
        assert r.render(make_scene(pose_true=np.array([4.0, 4.0, 0.0]))) is None
    finally:
        r.close()
        r.close()  # idempotent
    assert not pygame.display.get_init()


def test_human_mode_without_a_display_says_so(monkeypatch: pytest.MonkeyPatch) -> None:
    """No window system: SDL falls back to a driver that draws nowhere, and the env warns with the reason
    (once, when the window opens); where SDL cannot open any display, render raises with it."""
    import gymnasium as gym

    import ekfslam_gym  # noqa: F401

    for name in ("DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("SDL_VIDEODRIVER", "offscreen")
    env = gym.make("EKFSLAM-v0", render_mode="human")
    message = (
        r"driver is 'offscreen'.*SDL_VIDEODRIVER='offscreen', DISPLAY and WAYLAND_DISPLAY unset.*rgb_array"
    )
    try:
        with pytest.warns(UserWarning, match=message):
            env.reset(seed=0)  # human mode draws at reset and at every step
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # said once
            env.step(np.zeros(2, dtype=np.float32))
            assert env.render() is None
    finally:
        env.close()

    def no_video_device() -> None:
        raise pygame.error("No available video device")

    monkeypatch.setattr(pygame.display, "init", no_video_device)
    r = Renderer("human", width=W, height=H, options={"legend": False})
    with pytest.raises(
        RuntimeError, match=r"needs a display and SDL could not open one \(No available video"
    ):
        r.render(make_scene())


def test_bad_render_mode_lists_the_valid_ones() -> None:
    with pytest.raises(ValueError, match=r"rgb_array.*human"):
        Renderer("ansi")


def test_missing_pygame_says_how_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pygame", None)  # makes `import pygame` raise ImportError
    with pytest.raises(ImportError, match=r'pip install "ekfslam-gym\[render\]"'):
        Renderer("rgb_array")


def test_scene_is_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        make_scene().text = "changed"  # type: ignore[misc]


# ------------------------------------------------------------------------------------ what the sensor sees
def fov_pixels(frame: np.ndarray, legend_band: int = 0) -> np.ndarray:
    """(row, col) of every pixel shaded as the sensor's view (above the legend, whose sample is shaded too)."""
    return np.argwhere((frame[: len(frame) - legend_band] == np.array(render.FOV_FILL)).all(axis=-1))


def pixels_to_world(r: Renderer, bounds: np.ndarray, rows_cols: np.ndarray) -> np.ndarray:
    """World points (m) at the centres of pixels (row, col), the inverse of ``world_to_pixels``."""
    r.world_to_pixels(bounds, np.zeros(2))  # sets the scale and origin for these bounds
    col, row = rows_cols[:, 1] + 0.5, rows_cols[:, 0] + 0.5
    return np.stack([(col - r._ox) / r._scale, (r._oy - row) / r._scale], axis=1)


def crosses(start: np.ndarray, ends: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """For each end (n, 2): does the segment start-end cross the centre line of any wall (k, 4)?"""

    def orient(a, b, c):
        return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (
            c[..., 0] - a[..., 0]
        )

    p, q = np.broadcast_to(start, ends.shape)[:, None], ends[:, None]
    a, b = walls[None, :, :2], walls[None, :, 2:]
    proper = (orient(p, q, a) * orient(p, q, b) < 0) & (orient(a, b, p) * orient(a, b, q) < 0)
    return proper.any(axis=1)


BLOCKING = np.array([[0, 0, 10, 0], [10, 0, 10, 8], [10, 8, 0, 8], [0, 8, 0, 0], [4.5, 1.0, 4.5, 5.0]], float)


def test_field_of_view_stops_at_walls() -> None:
    """A wall 1.5 m ahead of the robot: no pixel behind it is shaded, though the open wedge reaches there."""
    r = Renderer("rgb_array", width=400, height=360, options={"legend": False})
    scene = make_scene(walls=BLOCKING, max_range=5.0, fov=np.pi / 2, read_ids=np.array([], int))
    frame = r.render(scene)
    bounds = scene.bounds
    shaded = pixels_to_world(r, bounds, fov_pixels(frame))
    assert len(shaded) > 500
    assert not crosses(scene.pose_true[:2], shaded, BLOCKING).any()
    # the check is not vacuous: the unoccluded wedge has many pixels behind that wall
    rows, cols = np.mgrid[0:360, 0:400]
    grid = pixels_to_world(r, bounds, np.stack([rows.ravel(), cols.ravel()], axis=1))
    d = grid - scene.pose_true[:2]
    in_wedge = (np.hypot(*d.T) < 5.0) & (np.abs(np.arctan2(d[:, 1], d[:, 0])) < np.pi / 4)
    assert crosses(scene.pose_true[:2], grid[in_wedge], BLOCKING).sum() > 500
    r.close()


def test_field_of_view_stays_inside_the_world() -> None:
    """No walls at all, a sensor reaching far: the shading ends at the world's edge."""
    r = Renderer("rgb_array", width=400, height=360, options={"legend": False})
    scene = make_scene(walls=np.zeros((0, 4)), max_range=50.0, fov=2 * np.pi, read_ids=np.array([], int))
    frame = r.render(scene)
    shaded = pixels_to_world(r, scene.bounds, fov_pixels(frame))
    assert len(shaded) > 1000
    half_px = 1.0 / r._scale
    assert (shaded >= scene.bounds[:2] - half_px).all() and (shaded <= scene.bounds[2:] + half_px).all()
    r.close()


def test_field_of_view_is_drawn_from_the_true_pose() -> None:
    """The shading is where the sensor is (it reads from the true pose), not where the filter thinks it is."""
    r = Renderer("rgb_array", width=400, height=360, options={"legend": False})
    scene = make_scene(
        walls=BLOCKING[:4], pose_est=np.array([8.0, 6.0, np.pi]), fov=np.pi / 3, read_ids=np.array([], int)
    )
    shaded = pixels_to_world(r, scene.bounds, fov_pixels(r.render(scene)))
    assert (shaded[:, 0] > 3.0).mean() > 0.99  # ahead of the true robot, facing +x
    r.close()


def test_legend_names_every_mark_in_its_own_band() -> None:
    with_legend = Renderer("rgb_array", width=640, height=640)
    without = Renderer("rgb_array", width=640, height=640, options={"legend": False})
    scene = make_scene()
    framed, plain = with_legend.render(scene), without.render(scene)
    bottom_of_world = with_legend.world_to_pixels(scene.bounds, np.array([0.0, 0.0]))[1]
    band = framed[int(bottom_of_world) + 4 :]
    assert len(band) >= 2 * render.LEGEND_ROW
    for colour in (render.TRUE_BODY, render.EST, render.LANDMARK_EST, render.FOV_FILL, render.TEXT):
        assert (band == np.array(colour)).all(axis=-1).any(), colour
    columns, font = with_legend._legend_columns, with_legend._legend_font()
    for i, (_, label, _) in enumerate(
        with_legend._legend_entries()
    ):  # every label inside the frame, none overlapping
        column = i % len(columns)
        right = columns[column] + render.LEGEND_MARK + font.size(label)[0]
        assert right <= (columns[column + 1] if column + 1 < len(columns) else 640 - render.PAD), label
    labels = [label for _, label, _ in with_legend._legend_entries()]
    assert {"true robot", "true landmark", "true path", "estimated path"} <= set(labels)
    # without the legend the map takes the whole frame
    assert without.world_to_pixels(scene.bounds, np.array([0.0, 0.0]))[1] > bottom_of_world
    assert not np.array_equal(framed, plain)
    with_legend.close()
    without.close()


def test_magnified_landmark_ellipses_are_larger_and_say_so(renderer: Renderer) -> None:
    big = Renderer("rgb_array", width=W, height=H, options={"legend": False, "landmark_ellipse_scale": 4})
    scene = make_scene(read_ids=np.array([], int))
    assert blue_pixels(big.render(scene)).sum() > 2 * blue_pixels(renderer.render(scene)).sum()
    assert any("\u00d74" in label for _, label, _ in big._legend_entries())
    big.close()


def test_render_options_reject_bad_values() -> None:
    with pytest.raises(ValueError, match="landmark_ellipse_scale"):
        render.RenderOptions(landmark_ellipse_scale=0.5)
    with pytest.raises(ValueError, match=r"no field \['colour'\].*legend, landmark_ellipse_scale"):
        render.RenderOptions.build({"colour": "red"})
    with pytest.raises(ValueError, match="legend"):
        Renderer("rgb_array", width=W, height=H)  # too small for the legend and a map


def test_pose_ellipse_is_drawn_over_the_robots(renderer: Renderer) -> None:
    """A 3-sigma pose ellipse of 1.5 m: its red line crosses the point 1.5 m to the estimate's side."""
    scene = make_scene(pose_cov=np.diag([0.25, 0.25, 0.01]), read_ids=np.array([], int))
    frame = renderer.render(scene)
    edge = renderer.world_to_pixels(scene.bounds, scene.pose_est[:2] + np.array([1.5, 0.0]))
    red = (frame[..., 0].astype(int) - frame[..., 1] > 120) & (frame[..., 2] < 100)
    col, row = np.round(edge).astype(int)
    assert red[row - 2 : row + 3, col - 2 : col + 3].any()


def test_env_frames_shade_no_pixel_behind_a_wall() -> None:
    """On the env's own frames (the corridor ring and the rooms, where walls are close on every side): the
    shaded view never reaches past a wall, step after step; and the header counts env steps."""
    import gymnasium as gym

    import ekfslam_gym  # noqa: F401

    for env_id in ("EKFSLAM-Loop-v0", "EKFSLAM-Large-v0"):
        env = gym.make(env_id, render_mode="rgb_array", action={"kind": "primitives"})
        env.reset(seed=3)
        base = env.unwrapped
        walls = np.asarray(base._world.layout.walls, dtype=float)
        checked = 0
        for step in range(6):
            frame = env.render()
            band = base._renderer._legend_band
            assert band > 0  # the env draws its legend
            shaded = pixels_to_world(base._renderer, base._bounds, fov_pixels(frame, band))
            assert len(shaded) > 100
            assert not crosses(base._world.pose[:2], shaded, walls).any(), (env_id, step)
            checked += len(shaded)
            env.step(step % 9)
        scenes: list[Scene] = []
        original = base._renderer.render
        base._renderer.render = lambda scene, seen=scenes, draw=original: seen.append(scene) or draw(scene)
        env.render()
        assert scenes[0].text.startswith(
            f"step 6/{base.config.max_episode_steps} "
        )  # 6 env steps, 60 controls
        assert base.elapsed_steps == 60
        env.close()


def test_rgb_array_render_is_a_non_blank_frame():
    pytest.importorskip("pygame")
    env = gym.make("EKFSLAM-v0", render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.array([0.5, 0.3]))
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.shape == (640, 640, 3)
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 5
    env.close()
