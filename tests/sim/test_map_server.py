"""A ROS map_server map as a layout: PGM (P2, P5) and PNG images read without new packages, walls around the
free space merged into runs, landmarks and start given or drawn, errors that name the file, an episode on a
map written by the test."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import ekfslam_gym  # noqa: F401  (registers the ids)
from ekfslam_gym.sim import World, make_layout
from ekfslam_gym.sim.geometry import min_wall_distance
from ekfslam_gym.sim.layout_base import wall_runs
from ekfslam_gym.sim.map_server import _boundary, load_map, read_image

FREE, OCCUPIED, UNKNOWN = 254, 0, 205  # map_saver's grey values


def floor_plan() -> np.ndarray:
    """A 40 x 60 px plan, row 0 at the top: two rooms joined by a door, an obstacle, and unknown space."""
    image = np.full((40, 60), FREE, dtype=np.uint8)
    image[:, :2] = image[:, -2:] = image[:2, :] = image[-2:, :] = OCCUPIED
    image[2:38, 30:32] = OCCUPIED  # the wall between the rooms
    image[16:24, 30:32] = FREE  # its door, 2 m wide at 0.25 m a pixel
    image[8:14, 10:16] = OCCUPIED  # a column in the left room
    image[28:38, 46:58] = UNKNOWN  # a corner never mapped
    return image


def write_pgm(path: Path, image: np.ndarray, binary: bool = True) -> None:
    rows, cols = image.shape
    if binary:
        path.write_bytes(b"P5\n# written by the test\n%d %d\n255\n" % (cols, rows) + image.tobytes())
    else:
        body = "\n".join(" ".join(map(str, row)) for row in image.tolist())
        path.write_text(f"P2\n# written by the test\n{cols} {rows}\n255\n{body}\n")


def write_png(path: Path, pixels: np.ndarray) -> None:
    """An 8-bit PNG (grey (rows, cols) or RGB (rows, cols, 3)), row r filtered with filter r mod 5, so the reader's
    five filters are all used."""
    rows, cols = pixels.shape[:2]
    step = 1 if pixels.ndim == 2 else pixels.shape[2]
    data = pixels.reshape(rows, cols * step).astype(np.int64)
    lines = []
    for r in range(rows):
        x = data[r]
        up = data[r - 1] if r else np.zeros_like(x)
        left = np.concatenate([np.zeros(step, dtype=np.int64), x[:-step]])
        up_left = np.concatenate([np.zeros(step, dtype=np.int64), up[:-step]])
        kind = r % 5
        if kind == 0:
            predictor = np.zeros_like(x)
        elif kind == 1:
            predictor = left
        elif kind == 2:
            predictor = up
        elif kind == 3:
            predictor = (left + up) // 2
        else:
            estimate = left + up - up_left
            pa, pb, pc = abs(estimate - left), abs(estimate - up), abs(estimate - up_left)
            predictor = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, up, up_left))
        lines.append(bytes([kind]) + ((x - predictor) % 256).astype(np.uint8).tobytes())

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    colour = 0 if pixels.ndim == 2 else 2
    header = struct.pack(">IIBBBBB", cols, rows, 8, colour, 0, 0, 0)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"".join(lines)))
        + chunk(b"IEND", b"")
    )  # fmt: skip


def write_map(folder: Path, image_name: str = "plan.pgm", extra: str = "", origin=(-2.0, 1.0, 0.0)) -> Path:
    yaml_path = folder / "plan.yaml"
    yaml_path.write_text(
        f"image: {image_name}\nresolution: 0.25\norigin: [{origin[0]}, {origin[1]}, {origin[2]}]\nnegate: 0\n"
        f"occupied_thresh: 0.65\nfree_thresh: 0.196\n{extra}"
    )
    return yaml_path


@pytest.fixture
def plan(tmp_path: Path) -> Path:
    write_pgm(tmp_path / "plan.pgm", floor_plan())
    return write_map(tmp_path)


def test_an_episode_runs_on_a_map_written_here(plan: Path) -> None:
    world = {"layout": "map_server", "n_landmarks": 12, "layout_kwargs": {"yaml": str(plan)}}
    env = gym.make("EKFSLAM-v0", world=world, max_episode_steps=60)
    obs, _ = env.reset(seed=4)
    layout = env.unwrapped.world.layout
    assert layout.name == "map_server" and layout.landmarks.shape == (12, 2)
    assert np.allclose(layout.bounds, [-2.0, 1.0, -2.0 + 60 * 0.25, 1.0 + 40 * 0.25])
    occupancy = load_map(plan)
    assert (
        occupancy.cell_is_free(layout.landmarks).all() and occupancy.cell_is_free(layout.start[None, :2])[0]
    )
    assert min_wall_distance(layout.landmarks, layout.walls).min() >= 0.5
    env.action_space.seed(1)
    for _ in range(60):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs) and np.isfinite(reward)
        if terminated or truncated:
            break
    assert truncated or terminated
    again = gym.make("EKFSLAM-v0", world=world)
    again.reset(seed=4)
    assert np.array_equal(again.unwrapped.world.layout.landmarks, layout.landmarks)


def test_walls_enclose_the_free_space_in_few_segments(plan: Path) -> None:
    layout = make_layout("map_server", np.random.default_rng(0), 5, yaml=str(plan))
    # the outline of the free space: outer box (4), the dividing wall with its door (6 runs: 2 x 2 faces
    # above and below the door, and its two ends), the column (4), the unknown corner (2 more runs)
    assert len(layout.walls) <= 20
    lengths = np.hypot(layout.walls[:, 2] - layout.walls[:, 0], layout.walls[:, 3] - layout.walls[:, 1])
    assert lengths.min() > 0.0
    # every free pixel's centre is clear of the walls by half a pixel, every wall lies on a pixel edge
    occupancy = load_map(plan)
    rows, cols = np.nonzero(occupancy.free)
    centres = np.column_stack([-2.0 + (cols + 0.5) * 0.25, 1.0 + (rows + 0.5) * 0.25])
    assert min_wall_distance(centres, layout.walls).min() >= 0.125 - 1e-12
    assert np.allclose(((layout.walls[:, [0, 2]] + 2.0) / 0.25) % 1.0, 0.0)


def test_wall_runs_merge_straight_runs_only() -> None:
    free = np.zeros((3, 4), dtype=bool)
    free[1, 1:3] = True  # a 1 x 2 free slot: 4 walls around it, the long sides one segment each
    walls = np.array(wall_runs(_boundary(free), 0.0, 0.0, 1.0, 1.0))
    expected = {(1.0, 1.0, 3.0, 1.0), (1.0, 2.0, 3.0, 2.0), (1.0, 1.0, 1.0, 2.0), (3.0, 1.0, 3.0, 2.0)}
    assert {tuple(w) for w in walls.tolist()} == expected


def test_p2_p5_and_png_read_alike(tmp_path: Path) -> None:
    image = floor_plan()
    write_pgm(tmp_path / "a.pgm", image)
    write_pgm(tmp_path / "b.pgm", image, binary=False)
    write_png(tmp_path / "c.png", image)
    for name in ("a.pgm", "b.pgm", "c.png"):
        assert np.array_equal(read_image(tmp_path / name), image.astype(float)), name
    colour = np.random.default_rng(0).integers(0, 256, (9, 11, 3), dtype=np.uint8)
    write_png(tmp_path / "d.png", colour)
    assert np.allclose(read_image(tmp_path / "d.png"), colour.mean(axis=-1))
    sixteen = tmp_path / "e.pgm"
    sixteen.write_bytes(b"P5 3 1 65535\n" + np.array([0, 65535, 32896], dtype=">u2").tobytes())
    assert np.allclose(read_image(sixteen), [[0.0, 255.0, 128.0]])


def test_a_png_floor_plan_runs_too(tmp_path: Path) -> None:
    write_png(tmp_path / "plan.png", floor_plan())
    yaml_path = write_map(tmp_path, "plan.png")
    layout = make_layout("map_server", np.random.default_rng(2), 8, yaml=str(yaml_path))
    World(layout)


def test_landmarks_and_start_given_in_the_yaml(tmp_path: Path) -> None:
    write_pgm(tmp_path / "plan.pgm", floor_plan())
    extra = "landmarks: [[1.0, 3.0], [9.0, 8.0], [5.0, 2.5]]\nstart: [0.0, 5.0, 1.5]\n"
    yaml_path = write_map(tmp_path, extra=extra)
    layout = make_layout("map_server", np.random.default_rng(0), 3, yaml=str(yaml_path))
    assert np.array_equal(layout.landmarks, [[1.0, 3.0], [9.0, 8.0], [5.0, 2.5]])
    assert np.array_equal(layout.start, [0.0, 5.0, 1.5])
    with pytest.raises(
        ValueError, match=r"plan\.yaml: the map lists 3 landmarks but world\.n_landmarks is 4"
    ):
        gym.make(
            "EKFSLAM-v0",
            world={"layout": "map_server", "n_landmarks": 4, "layout_kwargs": {"yaml": str(yaml_path)}},
        )


def test_downsampling_reads_coarser_cells(plan: Path) -> None:
    fine = make_layout("map_server", np.random.default_rng(0), 5, yaml=str(plan))
    coarse = make_layout("map_server", np.random.default_rng(0), 5, yaml=str(plan), downsample=2)
    assert np.array_equal(fine.bounds, coarse.bounds)  # 40 x 60 px divide by 2
    assert len(coarse.walls) <= len(fine.walls)


@pytest.mark.parametrize(
    ("yaml_text", "message"),
    [
        ("resolution: 0.25\norigin: [0, 0, 0]\n", "missing image"),
        ("image: plan.pgm\nresolution: -1\norigin: [0, 0, 0]\n", "resolution must be > 0"),
        ("image: plan.pgm\nresolution: 0.25\norigin: [0, 0]\n", "origin must be a list of 3 numbers"),
        ("image: plan.pgm\nresolution: 0.25\norigin: [0, 0, 0.5]\n", "origin yaw must be 0"),
        (
            "image: plan.pgm\nresolution: 0.25\norigin: [0, 0, 0]\nfree_thresh: 0.9\n",
            "free_thresh <= occupied",
        ),
        (
            "image: plan.pgm\nresolution: 0.25\norigin: [0, 0, 0]\nmode: raw\n",
            "mode must be trinary or scale",
        ),
        ("image: missing.pgm\nresolution: 0.25\norigin: [0, 0, 0]\n", r"missing\.pgm does not exist"),
        (
            "image: plan.pgm\nresolution: 0.25\norigin: [0, 0, 0]\nstart: [0.1, 0.1, 0]\n",
            "not in a free cell",
        ),
        ("image: plan.pgm\nresolution: 0.25\norigin: [0, 0, 0]\nlandmarks: [[0.1, 0.1]]\n", "landmark 0"),
        ("- just a list\n", "the top level must be a mapping"),
    ],
)
def test_errors_name_the_file_and_what_is_wrong(tmp_path: Path, yaml_text: str, message: str) -> None:
    write_pgm(tmp_path / "plan.pgm", floor_plan())
    yaml_path = tmp_path / "plan.yaml"
    yaml_path.write_text(yaml_text)
    with pytest.raises(ValueError, match=message) as error:
        make_layout("map_server", np.random.default_rng(0), 1, yaml=str(yaml_path))
    assert "plan.yaml" in str(error.value) or "missing.pgm" in str(error.value)


def test_a_bad_image_names_the_image(tmp_path: Path) -> None:
    (tmp_path / "plan.pgm").write_bytes(b"GIF89a not a map")
    with pytest.raises(ValueError, match=r"plan\.pgm: not a PGM"):
        make_layout("map_server", np.random.default_rng(0), 1, yaml=str(write_map(tmp_path)))
    (tmp_path / "plan.pgm").write_bytes(b"P5\n60 40\n255\n" + bytes(100))
    with pytest.raises(ValueError, match=r"plan\.pgm: 100 bytes of samples"):
        make_layout("map_server", np.random.default_rng(0), 1, yaml=str(write_map(tmp_path)))
