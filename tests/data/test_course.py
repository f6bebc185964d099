"""Readers and writers of the course's text formats (sensor_data.dat, world.dat)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ekfslam_gym.data.course import (
    CourseData,
    LandmarkMap,
    Step,
    read_sensor_data,
    read_world,
    write_sensor_data,
    write_world,
)
from tests.datapaths import freiburg_dir


def _course_file(name: str) -> Path:
    folder = freiburg_dir()
    if folder is None or not (folder / name).is_file():
        pytest.skip(
            f"course data {name} not found: set EKFSLAM_DATA_DIR to its folder (see tests/datapaths.py)"
        )
    return folder / name


# ------------------------------------------------------------------------------------------- the course file


def test_course_sensor_data_reads_every_block():
    data = read_sensor_data(_course_file("sensor_data.dat"))
    assert len(data) == 331  # the Octave reader's 330 plus the last block
    assert data.n_readings == 1212
    counts = dict(zip(*np.unique(data.readings_per_step(), return_counts=True), strict=True))
    assert counts == {2: 47, 3: 99, 4: 123, 5: 52, 6: 1, 7: 9}
    assert data.max_id == 9
    np.testing.assert_array_equal(data[0].odometry, [0.100692392654, 0.100072845247, 0.000171392857486])
    np.testing.assert_array_equal(data[0].ids, [1, 2])
    np.testing.assert_array_equal(
        data[0].z, [[1.89645381418, 0.374031885671], [3.85367751107, 1.51951017943]]
    )
    assert data[0].ids.dtype.kind == "i"
    odometry = np.array([step.odometry for step in data])
    assert np.all((odometry[:, 1] > 0.0994) & (odometry[:, 1] < 0.1005))


def test_course_sensor_data_keeps_odd_values_as_written():
    data = read_sensor_data(_course_file("sensor_data.dat"))
    ids = np.concatenate([step.ids for step in data])
    z = np.concatenate([step.z for step in data])
    negative = np.flatnonzero(z[:, 0] < 0)
    assert negative.tolist() == [int(np.flatnonzero(z[:, 0] == -0.035065641258)[0])]
    assert ids[negative[0]] == 7 and z[negative[0], 1] == 0.975887269646
    outside = (z[:, 1] <= -math.pi) | (z[:, 1] > math.pi)
    assert outside.sum() == 5  # not wrapped by the reader
    assert z[:, 1].min() == pytest.approx(-3.129, abs=1e-3) and z[:, 1].max() == pytest.approx(
        3.211, abs=1e-3
    )


def test_course_last_block_is_read():
    path = _course_file("sensor_data.dat")
    tail = path.read_text().splitlines()
    last_odometry = max(i for i, line in enumerate(tail) if line.startswith("ODOMETRY"))
    data = read_sensor_data(path)
    np.testing.assert_array_equal(data[-1].odometry, [float(v) for v in tail[last_odometry].split()[1:]])
    assert len(data[-1].ids) == len(tail) - last_odometry - 1


def test_course_world():
    world = read_world(_course_file("world.dat"))
    assert world.ids.tolist() == list(range(1, 10))
    expected = [(2, 1), (0, 4), (2, 7), (9, 2), (10, 5), (9, 8), (5, 5), (5, 3), (5, 9)]
    np.testing.assert_array_equal(world.positions, expected)
    assert world.as_dict()[5].tolist() == [10.0, 5.0]


# --------------------------------------------------------------------------------------------- malformed files

SENSOR_CASES = {
    "odometry token count": ("ODOMETRY 0.1 0.1 0.0\nODOMETRY 0.1 0.1\n", 2, "needs 3 values"),
    "sensor token count": ("ODOMETRY 0.1 0.1 0.0\nSENSOR 1 2.0 0.1 9\n", 2, "needs 3 values"),
    "non-numeric range": ("ODOMETRY 0.1 0.1 0.0\nSENSOR 1 2.0 0.1\nSENSOR 2 far 0.1\n", 3, "range 'far'"),
    "non-numeric odometry": ("ODOMETRY 0.1 x 0.0\n", 1, "t 'x'"),
    "non-finite bearing": ("ODOMETRY 0.1 0.1 0.0\nSENSOR 1 2.0 nan\n", 2, "not finite"),
    "non-integer id": ("ODOMETRY 0.1 0.1 0.0\nSENSOR 1.5 2.0 0.1\n", 2, "not an integer"),
    "zero id": ("ODOMETRY 0.1 0.1 0.0\nSENSOR 0 2.0 0.1\n", 2, "1-based"),
    "sensor before odometry": ("\nSENSOR 1 2.0 0.1\nODOMETRY 0.1 0.1 0.0\n", 2, "before any ODOMETRY"),
    "unknown tag": ("ODOMETRY 0.1 0.1 0.0\nSENSOR 1 2.0 0.1\nLASER 1 2 3\n", 3, "unknown tag 'LASER'"),
}


WORLD_CASES = {
    "token count": ("1 2 1\n2 0\n", 2, "needs 3 values"),
    "non-numeric": ("1 2 1\n2 0 y\n", 2, "y 'y'"),
    "duplicate id": ("1 2 1\n2 0 4\n1 3 3\n", 3, "already defined on line 1"),
    "bad id": ("one 2 1\n", 1, "not an integer"),
}


MALFORMED = [(read_sensor_data, case, *SENSOR_CASES[case]) for case in sorted(SENSOR_CASES)] + [
    (read_world, case, *WORLD_CASES[case]) for case in sorted(WORLD_CASES)
]


@pytest.mark.parametrize(
    ("reader", "case", "text", "line", "fragment"),
    MALFORMED,
    ids=[f"{reader.__name__}: {case}" for reader, case, *_ in MALFORMED],
)
def test_malformed_files_name_file_and_line(tmp_path, reader, case, text, line, fragment):
    path = tmp_path / "broken.dat"
    path.write_text(text)
    with pytest.raises(ValueError) as info:
        reader(path)
    message = str(info.value)
    assert f"broken.dat:{line}:" in message
    assert fragment in message


def test_blank_lines_and_empty_blocks(tmp_path):
    path = tmp_path / "s.dat"
    path.write_text("ODOMETRY 0 0.1 0\n\nODOMETRY 0.1 0.1 0.0\nSENSOR 3 1.0 -4.0\n   \nODOMETRY 0 0 0\n")
    data = read_sensor_data(path)
    assert data.readings_per_step().tolist() == [0, 1, 0]
    assert data[1].ids.tolist() == [3] and data[1].z.tolist() == [[1.0, -4.0]]
    assert data[0].z.shape == (0, 2) and data.head(2).n_readings == 1
    empty = tmp_path / "empty.dat"
    empty.write_text("")
    assert len(read_sensor_data(empty)) == 0 and read_sensor_data(empty).max_id == 0


# ----------------------------------------------------------------------------------------------- round trips


def test_writer_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(7)
    awkward = [1.0 / 3.0, -0.0, 1e-17, -123456.789e10, math.pi, 5e-324, 0.1 + 0.2]
    steps = [
        Step(
            np.array(awkward[:3]),
            np.array([4, 1]),
            np.array([[awkward[3], awkward[4]], [awkward[5], awkward[6]]]),
        ),
        Step(rng.normal(size=3), np.array([], dtype=int), np.zeros((0, 2))),
        Step(rng.normal(size=3), np.array([12]), rng.normal(size=(1, 2))),  # the last block has readings too
    ]
    original = CourseData(steps)
    back = read_sensor_data(write_sensor_data(tmp_path / "s.dat", original))
    assert len(back) == len(original)
    for a, b in zip(original, back, strict=True):
        assert a.odometry.tobytes() == b.odometry.tobytes()  # bit for bit, signed zero included
        np.testing.assert_array_equal(a.ids, b.ids)
        assert a.z.tobytes() == b.z.tobytes()

    world = LandmarkMap(np.array([9, 2, 5]), rng.normal(size=(3, 2)) * 1e3)
    world_back = read_world(write_world(tmp_path / "w.dat", world))
    np.testing.assert_array_equal(world_back.ids, [9, 2, 5])  # file order kept
    assert world_back.positions.tobytes() == world.positions.tobytes()
    assert world_back.sorted().ids.tolist() == [2, 5, 9]


def test_course_file_round_trip(tmp_path):
    data = read_sensor_data(_course_file("sensor_data.dat"))
    back = read_sensor_data(write_sensor_data(tmp_path / "sensor_data.dat", data))
    assert len(back) == 331 and back.n_readings == 1212
    for a, b in zip(data, back, strict=True):
        np.testing.assert_array_equal(a.odometry, b.odometry)
        np.testing.assert_array_equal(a.ids, b.ids)
        np.testing.assert_array_equal(a.z, b.z)


def test_step_and_world_validate_shapes():
    with pytest.raises(ValueError, match="2 ids but 1 readings"):
        Step(np.zeros(3), np.array([1, 2]), np.zeros((1, 2)))
    with pytest.raises(ValueError, match="not distinct"):
        LandmarkMap(np.array([1, 1]), np.zeros((2, 2)))
