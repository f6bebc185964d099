"""The readers' one line parser (``ekfslam_gym.data.records``): every text reader reports a broken line by its
file's full path and line number, and reads one encoding."""

from __future__ import annotations

import re

import pytest

from ekfslam_gym.data.course import read_sensor_data, read_world
from ekfslam_gym.data.g2o import read_g2o
from ekfslam_gym.data.gtsam2d import read_gtsam2d
from ekfslam_gym.data.mrclam import read_barcodes, read_landmark_truth, read_measurements, read_odometry
from ekfslam_gym.data.records import ENCODING, read_records
from ekfslam_gym.data.tum import read_tum

# (reader, file name, text whose line 2 is broken)
BROKEN_LINE_TWO = [
    (read_sensor_data, "sensor_data.dat", "ODOMETRY 0.1 0.1 0.0\nSENSOR 1 far 0.1\n"),
    (read_world, "world.dat", "1 2 1\n2 0 y\n"),
    (read_odometry, "Robot1_Odometry.dat", "1.0 0.1 0.0\n2.0 0.1 x\n"),
    (read_measurements, "Robot1_Measurement.dat", "1.0 72 2.0 0.1\n2.0 72 2.0\n"),
    (read_barcodes, "Barcodes.dat", "1 5\n2 five\n"),
    (read_landmark_truth, "Landmark_Groundtruth.dat", "6 1 2 0 0\n7 1 2 0 -1\n"),
    (read_gtsam2d, "victoria_park.txt", "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 x 0\n"),
    (read_g2o, "graph.g2o", "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0\n"),
    (read_tum, "run.tum", "0 0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n"),
]


@pytest.mark.parametrize(("reader", "name", "text"), BROKEN_LINE_TWO, ids=[r[1] for r in BROKEN_LINE_TWO])
def test_every_reader_names_the_full_path_and_the_line(tmp_path, reader, name, text):
    path = tmp_path / "deep" / "folder" / name
    path.parent.mkdir(parents=True)
    path.write_text(text, encoding=ENCODING)
    with pytest.raises(ValueError) as info:
        reader(path)
    assert str(info.value).startswith(f"{path}:2: "), str(info.value)


@pytest.mark.parametrize(("reader", "name", "text"), BROKEN_LINE_TWO, ids=[r[1] for r in BROKEN_LINE_TWO])
def test_a_byte_that_is_not_utf8_fails_on_its_line(tmp_path, reader, name, text):
    """One encoding for all: a stray Latin-1 byte is not read as something else, it fails where it is."""
    first = text.splitlines()[0]
    path = tmp_path / name
    path.write_bytes(b"\n" + first[:-1].encode() + b"\xb5\n")  # its last digit as Latin-1's micro sign
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}:2: .*\ufffd"):
        reader(path)


def test_records_skip_blank_lines_and_comments_and_keep_line_numbers(tmp_path):
    path = tmp_path / "a.dat"
    path.write_text("# café, a comment in UTF-8\n\n1 2 # the rest\n  3\t4  \n", encoding=ENCODING)
    assert [(r.line, r.tokens) for r in read_records(path)] == [(3, ["1", "2"]), (4, ["3", "4"])]
    assert [r.line for r in read_records(path, comment=None)] == [1, 3, 4]


def test_a_record_checks_its_fields(tmp_path):
    path = tmp_path / "a.dat"
    path.write_text("TAG 1 inf x -2\n")
    (record,) = read_records(path)
    assert record.where == f"{path}:1"
    record.expect(4, "TAG", tagged=True)
    with pytest.raises(ValueError, match=r":1: TAG line needs 3 values, got 4: 'TAG 1 inf x -2'$"):
        record.expect(3, "TAG", tagged=True)
    assert record.number(1, "a") == 1.0 and record.integer(1, "id", minimum=0) == 1
    with pytest.raises(ValueError, match="b 'inf' is not finite"):
        record.number(2, "b")
    with pytest.raises(ValueError, match="c 'x' is not a number"):
        record.number(3, "c")
    with pytest.raises(ValueError, match="id 'x' is not an integer"):
        record.integer(3, "id")
    with pytest.raises(ValueError, match="id -2 must be >= 0"):
        record.integer(4, "id", minimum=0)


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.dat"):
        list(read_records(tmp_path / "nope.dat"))
