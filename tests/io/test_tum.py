"""TUM trajectory files: exact round trip, comments, bad lines."""

import numpy as np
import pytest

from evpose.core.trajectory import Trajectory
from evpose.errors import InputError
from evpose.io.text_table import TimeUnit
from evpose.io.tum import is_tum_file, read_tum, write_tum


def test_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(0)
    tr = Trajectory.from_arrays(np.arange(5) * 33_333 + 1_468_939_993_067_000, rng.normal(size=(5, 3)), rng.normal(size=(5, 4)))
    write_tum(tmp_path / "t.txt", tr)
    back = read_tum(tmp_path / "t.txt")
    np.testing.assert_array_equal(back.t, tr.t)
    np.testing.assert_array_equal(back.position, tr.position)
    np.testing.assert_allclose(back.quat_xyzw, tr.quat_xyzw, atol=1e-15, rtol=0)
    assert is_tum_file(tmp_path / "t.txt")


def test_reads_comments_and_microsecond_files(tmp_path):
    f = tmp_path / "mocap_data.txt"
    f.write_text("# timestamp tx ty tz qx qy qz qw\n1000 1 2 3 0 0 0 1\n2000 1 2 3 0 0 0 1\n")
    assert read_tum(f, unit=TimeUnit.MICROSECONDS).t.tolist() == [1000, 2000]


@pytest.mark.parametrize(
    "text, message",
    [
        ("0.1 1 2 3 0 0 0 1\n0.1 1 2 3 0 0 0 1\n", "line 2: timestamp 0.1 does not increase"),
        ("0.1 1 2 3 0 0 0\n", "line 1: expected 8 values, got 7"),
        ("0.1 1 2 inf 0 0 0 1\n", "line 1: NaN or infinite value"),
        ("x 1 2 3 0 0 0 1\n", "line 1: timestamp 'x' is not a finite number"),
        ("# only a comment\n", "contains no poses"),
    ],
)
def test_bad_files_name_the_line(tmp_path, text, message):
    f = tmp_path / "t.txt"
    f.write_text(text)
    with pytest.raises(InputError, match=message):
        read_tum(f)


def test_write_refuses_to_overwrite_its_input(tmp_path):
    f = tmp_path / "t.txt"
    f.write_text("0.1 1 2 3 0 0 0 1\n")
    with pytest.raises(InputError, match="refusing"):
        write_tum(f, read_tum(f), inputs=(f,))


def test_zero_quaternion_names_its_line_like_every_other_tum_error(tmp_path):
    path = tmp_path / "est.txt"
    path.write_text("# header\n0.0 0 0 0 0 0 0 1\n\n0.1 0 0 0 0 0 0 0\n")
    with pytest.raises(InputError, match=r"est.txt: line 4: quaternion has zero length"):
        read_tum(path)


def test_quaternion_beyond_the_float_range_names_its_line_without_numpy_warnings(tmp_path):
    import warnings

    path = tmp_path / "est.txt"
    path.write_text("0.0 0 0 0 0 0 0 1\n0.1 0 0 0 1e300 0 0 1\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # np.linalg.norm's overflow warning was printed before the error line
        with pytest.raises(InputError, match=r"est.txt: line 2: quaternion's length is beyond the float range"):
            read_tum(path)


def test_position_beyond_the_earth_names_its_line(tmp_path):
    path = tmp_path / "est.txt"
    path.write_text("# t tx ty tz qx qy qz qw\n0.0 0 0 0 0 0 0 1\n0.1 1e12 0 0 0 0 0 1\n")
    with pytest.raises(InputError, match=r"est.txt: line 3: position \[1000000000000.0, 0.0, 0.0\] is beyond 1e\+07 m"):
        read_tum(path)
