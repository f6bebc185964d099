"""The pygame renderer: headless frames that show what the scene says, and nothing for what it does not."""

from __future__ import annotations

import dataclasses
import sys
import time
import warnings

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
    r = Renderer("rgb_array", width=W, height=H)
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
    r = Renderer("rgb_array", width=W, height=H)
    r.render(make_scene())
    r.close()
    assert not pygame.display.get_init()


def test_human_mode_runs_headless(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    r = Renderer("human", width=W, height=H, fps=1000)
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
    r = Renderer("human", width=W, height=H)
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
