"""A ROS ``map_server`` map as a layout: the floor plan every robotics user already has.

The map is the ROS format as it is: a YAML file with ``image`` (a PGM, P2 or P5, or a PNG, relative to the
YAML's folder), ``resolution`` (m per pixel), ``origin`` ([x, y, yaw] of the lower-left pixel; yaw must be 0),
``negate``, ``occupied_thresh`` and ``free_thresh`` (defaults 0, 0.65 and 0.196, map_saver's values), and
optionally ``mode`` (``trinary``, the default, or ``scale``: both read the thresholds alike here). Row 0 of the
image is the top of the map. A pixel's occupancy is p = (255 - v) / 255 (v / 255 with ``negate``), v the
pixel's value scaled to 0-255 (colour channels averaged, alpha ignored); it is free when p < free_thresh,
occupied when p > occupied_thresh, unknown in between.

Two keys of our own may be added: ``landmarks`` ([[x, y], ...], m, in the map's frame: used as they are, and
``world.n_landmarks`` must equal their number) and ``start`` ([x, y, theta], m and rad). Without them the
landmarks are placed as in every generated layout and the start is drawn at the centre of a free cell of the
map's largest open region, ``start_clearance`` from the walls, with a uniform heading.

Walls: the boundary of the free space. Every edge between a free pixel and one that is not free (occupied,
unknown, or outside the image) is a wall, and each straight run of such edges is merged into one segment, so
unknown space counts as solid and the robot stays inside the mapped free space. Reading the images needs no
package beyond numpy (PGM: the header and the samples; PNG: zlib and the five row filters, 8 or 16 bits per
sample, not interlaced). A map is read once per file version and kept (``_maps``).
"""

from __future__ import annotations

import math
import os
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import compiled
from .layout_base import Layout, check_int, place_landmarks, wall_runs

ROS_DEFAULTS = {"negate": 0, "occupied_thresh": 0.65, "free_thresh": 0.196, "mode": "trinary"}


@dataclass(frozen=True, eq=False)
class OccupancyMap:
    """A map read from its YAML: free (rows, cols) bool with row 0 at the bottom, the walls around the free
    space, the bounds, the cells a start may be drawn at, and the landmarks and start the YAML gives (or
    None)."""

    path: Path
    free: np.ndarray
    cell: float
    walls: np.ndarray
    bounds: np.ndarray
    start_cells: np.ndarray
    landmarks: np.ndarray | None
    start: np.ndarray | None

    def cell_is_free(self, points: np.ndarray) -> np.ndarray:
        """Whether each point (k, 2) lies inside the map, in a free cell."""
        cols = np.floor((points[:, 0] - self.bounds[0]) / self.cell).astype(np.int64)
        rows = np.floor((points[:, 1] - self.bounds[1]) / self.cell).astype(np.int64)
        inside = (rows >= 0) & (rows < self.free.shape[0]) & (cols >= 0) & (cols < self.free.shape[1])
        ok = np.zeros(len(points), dtype=bool)
        ok[inside] = self.free[rows[inside], cols[inside]]
        return ok


_MAPS_KEPT = 8
_maps: dict[tuple, OccupancyMap] = {}


def map_server(
    rng: np.random.Generator,
    n_landmarks: int = 30,
    *,
    yaml: str,
    downsample: int = 1,
    min_spacing: float = 1.0,
    landmark_clearance: float = 0.5,
    start_clearance: float = 1.0,
    robot_radius: float = 0.2,
    wall_radius: float = 0.05,
) -> Layout:
    """A ROS map_server map (the module's docstring has the format): walls around its free space, the
    landmarks and start its YAML gives or drawn, the map's own frame and extent.

    Keywords:
        yaml: the map's YAML file (a path, relative to the working directory).
        downsample: read the map at this many pixels a cell (a cell is free when all its pixels are): fewer,
            longer walls for a fine map.
    """
    check_int("downsample", downsample, 1)
    occupancy = load_map(yaml, downsample, start_clearance)
    where = occupancy.path
    if occupancy.start is not None:
        start = occupancy.start
        needed = robot_radius + wall_radius
        if not occupancy.cell_is_free(start[None, :2])[0]:
            raise ValueError(f"{where}: start {start.tolist()} is not in a free cell of the map")
        if compiled.min_wall_distance(start[None, :2], occupancy.walls)[0] < needed:
            raise ValueError(
                f"{where}: start {start.tolist()} is within {needed} m of a wall (the robot's body)"
            )
    else:
        if len(occupancy.start_cells) == 0:
            raise ValueError(f"{where}: no free cell lies {start_clearance} m from every wall to start at")
        xy = occupancy.start_cells[int(rng.integers(len(occupancy.start_cells)))]
        start = np.array([xy[0], xy[1], rng.uniform(-math.pi, math.pi)])
    if occupancy.landmarks is not None:
        landmarks = occupancy.landmarks
        if len(landmarks) != n_landmarks:
            raise ValueError(
                f"{where}: the map lists {len(landmarks)} landmarks but world.n_landmarks is {n_landmarks}"
            )
        outside = np.flatnonzero(~occupancy.cell_is_free(landmarks))
        if len(outside):
            raise ValueError(f"{where}: landmark {int(outside[0])} {landmarks[outside[0]].tolist()} is not in a "
                             "free cell of the map")  # fmt: skip
    else:
        try:
            landmarks = place_landmarks(
                rng, n_landmarks, occupancy.walls, occupancy.bounds, start, min_spacing=min_spacing,
                landmark_clearance=landmark_clearance, robot_radius=robot_radius, wall_radius=wall_radius,
            )  # fmt: skip
        except ValueError as error:
            raise ValueError(f"{where}: {error}") from None
    return Layout("map_server", occupancy.walls, landmarks, start, occupancy.bounds, wall_radius)


def load_map(yaml_path: str | os.PathLike, downsample: int = 1, start_clearance: float = 1.0) -> OccupancyMap:
    """The map of a map_server YAML, read once per file version (path, size and modification time) and kept;
    ValueError naming the file and what is wrong."""
    path = Path(yaml_path).expanduser().resolve()
    if not path.is_file():
        raise ValueError(f"map YAML {yaml_path} does not exist")
    stat = path.stat()
    key = (str(path), stat.st_mtime_ns, stat.st_size, int(downsample), float(start_clearance))
    occupancy = _maps.get(key)
    if occupancy is None:
        occupancy = _read(path, int(downsample), float(start_clearance))
        if len(_maps) >= _MAPS_KEPT:
            del _maps[next(iter(_maps))]
        _maps[key] = occupancy
    return occupancy


def _read(path: Path, downsample: int, start_clearance: float) -> OccupancyMap:
    import yaml

    try:
        spec = yaml.safe_load(path.read_text())
    except yaml.YAMLError as error:
        raise ValueError(f"{path}: not valid YAML ({error})") from None
    if not isinstance(spec, dict):
        raise ValueError(f"{path}: the top level must be a mapping with image, resolution and origin")
    spec = {**ROS_DEFAULTS, **spec}
    missing = [key for key in ("image", "resolution", "origin") if key not in spec]
    if missing:
        raise ValueError(
            f"{path}: missing {', '.join(missing)} (a map_server YAML has image, resolution, origin)"
        )
    resolution = _number(path, "resolution", spec["resolution"])
    if resolution <= 0.0:
        raise ValueError(f"{path}: resolution must be > 0 m per pixel, got {resolution!r}")
    origin = _vector(path, "origin", spec["origin"], 3)
    if origin[2] != 0.0:
        raise ValueError(f"{path}: origin yaw must be 0 (a rotated map is not supported), got {origin[2]!r}")
    negate = spec["negate"]
    if negate not in (0, 1, True, False):
        raise ValueError(f"{path}: negate must be 0 or 1, got {negate!r}")
    occupied = _number(path, "occupied_thresh", spec["occupied_thresh"])
    free_below = _number(path, "free_thresh", spec["free_thresh"])
    if not 0.0 <= free_below <= occupied <= 1.0:
        raise ValueError(
            f"{path}: need 0 <= free_thresh <= occupied_thresh <= 1, got {free_below}, {occupied}"
        )
    if spec["mode"] not in ("trinary", "scale"):
        raise ValueError(f"{path}: mode must be trinary or scale, got {spec['mode']!r}")

    image_path = path.parent / str(spec["image"])
    values = read_image(image_path)  # (rows, cols) float in [0, 255], row 0 at the top
    p = values / 255.0 if negate else (255.0 - values) / 255.0
    free = (p < free_below)[::-1]  # row 0 at the bottom, as y grows
    if downsample > 1:
        rows, cols = free.shape[0] // downsample, free.shape[1] // downsample
        if rows == 0 or cols == 0:
            raise ValueError(f"{path}: downsample {downsample} leaves no cell of a {free.shape} image")
        free = free[: rows * downsample, : cols * downsample]
        free = free.reshape(rows, downsample, cols, downsample).all(axis=(1, 3))
    free = np.ascontiguousarray(free)
    if not free.any():
        raise ValueError(f"{image_path}: no pixel is free (p < free_thresh {free_below})")
    cell = resolution * downsample
    rows, cols = free.shape
    bounds = np.array([origin[0], origin[1], origin[0] + cols * cell, origin[1] + rows * cell])
    walls = np.array(wall_runs(_boundary(free), origin[0], origin[1], cell, cell), dtype=np.float64).reshape(
        -1, 4
    )
    landmarks = start = None
    if spec.get("landmarks") is not None:
        landmarks = _points(path, spec["landmarks"])
    if spec.get("start") is not None:
        start = _vector(path, "start", spec["start"], 3)
    free.flags.writeable = False
    return OccupancyMap(path, free, cell, walls, bounds, _start_cells(free, walls, bounds, cell, start_clearance),
                        landmarks, start)  # fmt: skip


def _boundary(free: np.ndarray) -> np.ndarray:
    """The closed edges (``wall_runs``' layout) between free cells and the rest (outside the grid included)."""
    rows, cols = free.shape
    padded = np.zeros((rows + 2, cols + 2), dtype=bool)
    padded[1:-1, 1:-1] = free
    closed = np.zeros((2, rows + 1, cols + 1), dtype=bool)
    closed[0, :, :cols] = padded[:-1, 1:-1] != padded[1:, 1:-1]
    closed[1, :rows, :] = padded[1:-1, :-1] != padded[1:-1, 1:]
    return closed


def _start_cells(
    free: np.ndarray, walls: np.ndarray, bounds: np.ndarray, cell: float, clearance: float
) -> np.ndarray:
    """Centres (k, 2) of the free cells ``clearance`` from every wall in the largest region such cells make:
    a drawn start there has room to move and landmarks around it."""
    from scipy import ndimage

    rows, cols = free.shape
    roomy = free & compiled.free_cells(walls, float(bounds[0]), float(bounds[1]), cell, rows, cols, clearance)
    labels, count = ndimage.label(roomy)
    if count == 0:
        return np.empty((0, 2))
    largest = 1 + int(np.argmax(np.bincount(labels.ravel())[1:]))
    r, c = np.nonzero(labels == largest)
    return np.column_stack([bounds[0] + (c + 0.5) * cell, bounds[1] + (r + 0.5) * cell])


def _number(path: Path, key: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{path}: {key} must be a number, got {value!r}")
    return float(value)


def _vector(path: Path, key: str, value: object, length: int) -> np.ndarray:
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise ValueError(f"{path}: {key} must be a list of {length} numbers, got {value!r}")
    return np.array([_number(path, key, v) for v in value])


def _points(path: Path, value: object) -> np.ndarray:
    if not isinstance(value, (list, tuple)) or not value:
        raise ValueError(f"{path}: landmarks must be a non-empty list of [x, y], got {value!r}")
    return np.array([_vector(path, f"landmarks[{i}]", point, 2) for i, point in enumerate(value)])


# ------------------------------------------------------------------------------------------------- images
def read_image(path: Path) -> np.ndarray:
    """A PGM (P2, P5) or PNG image as (rows, cols) float64 grey values in [0, 255], row 0 at the top."""
    if not path.is_file():
        raise ValueError(f"map image {path} does not exist")
    data = path.read_bytes()
    if data[:2] in (b"P2", b"P5"):
        return _read_pgm(path, data)
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        return _read_png(path, data)
    raise ValueError(f"{path}: not a PGM (P2 or P5) or PNG image")


def _read_pgm(path: Path, data: bytes) -> np.ndarray:
    """PGM: a header of four whitespace-separated tokens (magic, width, height, maxval; ``#`` starts a
    comment), then the samples: ASCII numbers (P2) or binary after one whitespace byte (P5, two bytes
    big-endian when maxval > 255)."""
    tokens: list[bytes] = []
    i = 2
    while len(tokens) < 3:
        while i < len(data) and data[i : i + 1].isspace():
            i += 1
        if data[i : i + 1] == b"#":
            while i < len(data) and data[i : i + 1] not in (b"\n", b"\r"):
                i += 1
            continue
        j = i
        while j < len(data) and not data[j : j + 1].isspace() and data[j : j + 1] != b"#":
            j += 1
        if j == i:
            raise ValueError(f"{path}: truncated PGM header")
        tokens.append(data[i:j])
        i = j
    try:
        width, height, maxval = (int(t) for t in tokens)
    except ValueError:
        raise ValueError(f"{path}: the PGM header's width, height and maxval must be integers") from None
    if width < 1 or height < 1 or not 0 < maxval < 65536:
        raise ValueError(f"{path}: bad PGM size {width} x {height} or maxval {maxval}")
    count = width * height
    if data[:2] == b"P5":
        body = data[i + 1 :]
        dtype = np.dtype(">u2") if maxval > 255 else np.dtype(np.uint8)
        if len(body) < count * dtype.itemsize:
            raise ValueError(f"{path}: {len(body)} bytes of samples, a {width} x {height} image needs "
                             f"{count * dtype.itemsize}")  # fmt: skip
        samples = np.frombuffer(body, dtype=dtype, count=count)
    else:
        try:
            samples = np.array(data[i:].split(), dtype=np.int64)
        except ValueError:
            raise ValueError(f"{path}: a P2 sample is not an integer") from None
        if len(samples) < count:
            raise ValueError(f"{path}: {len(samples)} samples, a {width} x {height} image needs {count}")
        samples = samples[:count]
    return samples.reshape(height, width).astype(np.float64) * (255.0 / maxval)


_PNG_CHANNELS = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}  # colour type: samples a pixel


def _read_png(path: Path, data: bytes) -> np.ndarray:
    """PNG, 8 or 16 bits a sample, any colour type, not interlaced: the chunks, zlib, the row filters."""
    position = 8
    header = palette = None
    compressed = []
    while position + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[position : position + 8])
        body = data[position + 8 : position + 8 + length]
        position += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"PLTE":
            palette = np.frombuffer(body, dtype=np.uint8).reshape(-1, 3).astype(np.float64)
        elif kind == b"IDAT":
            compressed.append(body)
        elif kind == b"IEND":
            break
    if header is None or not compressed:
        raise ValueError(f"{path}: a PNG without IHDR or IDAT")
    width, height, depth, colour, _, _, interlace = header
    if depth not in (8, 16) or colour not in _PNG_CHANNELS or interlace:
        raise ValueError(f"{path}: PNG with {depth}-bit samples, colour type {colour}, interlace {interlace}; "
                         "save it as 8-bit, not interlaced (or as PGM)")  # fmt: skip
    channels = _PNG_CHANNELS[colour]
    step = channels * depth // 8  # bytes a pixel
    stride = width * step
    try:
        raw = np.frombuffer(zlib.decompress(b"".join(compressed)), dtype=np.uint8)
    except zlib.error as error:
        raise ValueError(f"{path}: corrupt PNG data ({error})") from None
    if len(raw) < height * (stride + 1):
        raise ValueError(f"{path}: PNG data too short for {width} x {height}")
    rows = raw[: height * (stride + 1)].reshape(height, stride + 1)
    pixels = np.zeros((height, stride), dtype=np.uint8)
    previous = np.zeros(stride, dtype=np.uint8)
    for r in range(height):
        kind, line = rows[r, 0], rows[r, 1:].astype(np.int64)
        if kind == 0:
            out = line
        elif kind == 1:  # Sub: x = f + x[left], a running sum per byte of the pixel
            out = np.cumsum(line.reshape(width, step), axis=0).reshape(-1)
        elif kind == 2:  # Up
            out = line + previous
        elif kind in (3, 4):  # Average, Paeth: each byte depends on the reconstructed byte to its left
            out = _unfilter_sequential(kind, line, previous.astype(np.int64), step)
        else:
            raise ValueError(f"{path}: PNG row {r} has unknown filter {kind}")
        pixels[r] = previous = (out % 256).astype(np.uint8)
    if depth == 16:
        samples = pixels.reshape(height, width * channels, 2).astype(np.float64)
        samples = (samples[..., 0] * 256.0 + samples[..., 1]) * (255.0 / 65535.0)
    else:
        samples = pixels.astype(np.float64)
    samples = samples.reshape(height, width, channels)
    if colour == 3:
        if palette is None:
            raise ValueError(f"{path}: a palette PNG without PLTE")
        return palette[samples[..., 0].astype(np.int64)].mean(axis=-1)
    grey_channels = 1 if colour in (0, 4) else 3  # the alpha channel is ignored
    return samples[..., :grey_channels].mean(axis=-1)


def _unfilter_sequential(kind: int, line: np.ndarray, above: np.ndarray, step: int) -> np.ndarray:
    out = line.copy()
    for i in range(len(line)):
        left = out[i - step] if i >= step else 0
        if kind == 3:
            out[i] = (line[i] + (left + above[i]) // 2) % 256
        else:
            up_left = above[i - step] if i >= step else 0
            estimate = left + above[i] - up_left
            pa, pb, pc = abs(estimate - left), abs(estimate - above[i]), abs(estimate - up_left)
            predictor = left if pa <= pb and pa <= pc else (above[i] if pb <= pc else up_left)
            out[i] = (line[i] + predictor) % 256
    return out
