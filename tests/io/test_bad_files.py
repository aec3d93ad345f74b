"""Damaged maps, clouds, config files and event texts: each is one InputError naming the file (and the record where
there is one), raised before any allocation the file's header asks for and without a C library's own stderr noise."""

import os

import numpy as np
import pytest

from evpose.errors import InputError
from evpose.io.config_file import read_config
from evpose.io.map_ply import read_contour_map, read_point_cloud, write_contour_map
from evpose.io.open import open_recording
from evpose.core.contour_map import ContourMap
from evpose.tracker.config import TrackerConfig

_HEADER = "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"


def _one_line(exc_info, path) -> str:
    msg = str(exc_info.value)
    assert msg.startswith(str(path)) and "\n" not in msg
    return msg


@pytest.mark.parametrize("reader", [read_contour_map, read_point_cloud])
def test_vertex_count_beyond_the_file_is_refused_before_allocating(tmp_path, reader):
    path = tmp_path / "huge.ply"
    path.write_text(_HEADER.format(n=99_999_999_999) + "1 2 3\n")
    with pytest.raises(InputError) as info:
        reader(path)
    assert "header promises 99999999999 vertices" in _one_line(info, path)


@pytest.mark.parametrize("count", ["-5", "many"])
def test_bad_vertex_count_names_the_header_line(tmp_path, count):
    path = tmp_path / "bad.ply"
    path.write_text(_HEADER.replace("{n}", count))
    with pytest.raises(InputError) as info:
        read_contour_map(path)
    assert "header line 3: expected 'element NAME COUNT' with a non-negative count" in _one_line(info, path)


def test_header_without_format_line_is_named(tmp_path):
    path = tmp_path / "nofmt.ply"
    path.write_text(_HEADER.format(n=1).replace("format ascii 1.0\n", "") + "1 2 3\n")
    with pytest.raises(InputError) as info:
        read_contour_map(path)
    assert "PLY header has no 'format' line" in _one_line(info, path)


def test_vertices_without_coordinates_are_named_not_an_empty_cloud(tmp_path):
    path = tmp_path / "noxyz.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float a\nend_header\n1\n")
    with pytest.raises(InputError) as info:
        read_contour_map(path)
    assert "vertices have no x, y, z properties" in _one_line(info, path)


def test_truncated_binary_cloud_is_refused_not_read_as_half_a_scan(tmp_path):
    # open3d returned the vertices before the cut (and printed "RPly: Error reading ..." itself).
    path = tmp_path / "map.ply"
    write_contour_map(path, ContourMap.from_points(np.random.default_rng(0).normal(size=(1000, 3))))
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError) as info:
        read_point_cloud(path)
    assert "file is truncated: header promises 1000 vertices" in _one_line(info, path)


def test_unparsable_ascii_cloud_is_our_error_and_open3d_prints_nothing(tmp_path, capfd):
    path = tmp_path / "text.ply"
    path.write_text(_HEADER.format(n=2) + "x y z\n")
    with pytest.raises(InputError) as info:
        read_point_cloud(path)
    assert "malformed PLY (RPly: Error reading 'x' of 'vertex' number 0)" in _one_line(info, path)
    assert "RPly" not in capfd.readouterr().err


def test_binary_config_file_is_not_a_text_file(tmp_path):
    path = tmp_path / "cfg.yaml"
    path.write_bytes(bytes(range(128, 256)))
    with pytest.raises(InputError) as info:
        read_config(TrackerConfig, path)
    assert "not a text file" in _one_line(info, path)


@pytest.mark.parametrize("name, text, message", [
    ("cfg.yaml", "rate_hz: [1, 2\n  : :\n", "line 2: not valid YAML (expected ',' or ']', but got ':')"),
    ("cfg.json", '{"rate_hz": }', "line 1: not valid JSON (Expecting value)"),
    # The parsers kept the last of two values silently; `false` or `0` was read as an empty file (all defaults).
    ("cfg.yaml", "rate_hz: 200\nregistration:\n  max_iterations: 5\nrate_hz: 300\n", "line 4: not valid YAML (duplicate key 'rate_hz')"),
    ("cfg.json", '{"rate_hz": 200, "rate_hz": 300}', "not valid JSON (duplicate key 'rate_hz')"),
    ("cfg.yaml", "false\n", "expected a mapping, got bool"),
])
def test_malformed_config_syntax_a_key_given_twice_or_a_falsy_document_is_one_line_naming_it(tmp_path, name, text, message):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputError) as info:
        read_config(TrackerConfig, path)
    assert message in _one_line(info, path)


@pytest.mark.parametrize("value", ["fast", "[1]"])
def test_config_number_of_the_wrong_type_says_a_number_is_expected(tmp_path, value):
    path = tmp_path / "cfg.yaml"
    path.write_text(f"rate_hz: {value}\n")
    with pytest.raises(InputError) as info:
        read_config(TrackerConfig, path)
    assert "rate_hz: expected a number, got" in _one_line(info, path)


def test_negative_ecd_timestamp_is_refused(tmp_path):
    d = tmp_path / "ecd"
    d.mkdir()
    (d / "events.txt").write_text("-0.0001 1 2 1\n0.0002 3 4 0\n")
    with pytest.raises(InputError) as info:
        open_recording(d, 240, 180)
    assert "event 0: timestamp -100 us is negative" in _one_line(info, d)


def test_check_config_walks_nested_numbers_and_names_the_dotted_field():
    import dataclasses

    from evpose.io.config_file import check_config

    cfg = TrackerConfig()
    check_config(cfg)  # the defaults are valid
    nested = next(f.name for f in dataclasses.fields(cfg) if dataclasses.is_dataclass(getattr(cfg, f.name))
                  and any(isinstance(getattr(getattr(cfg, f.name), g.name), float) for g in dataclasses.fields(getattr(cfg, f.name))))
    sub = getattr(cfg, nested)
    field = next(g.name for g in dataclasses.fields(sub) if isinstance(getattr(sub, g.name), float))
    setattr(sub, field, float("nan"))
    with pytest.raises(InputError, match=rf"{nested}\.{field}: expected a finite number, got nan"):
        check_config(cfg)


def test_a_folder_given_for_a_map_or_a_table_is_called_a_folder_not_missing(tmp_path):
    from evpose.io.text_table import read_table

    (tmp_path / "map.ply").mkdir()
    (tmp_path / "gt.txt").mkdir()
    with pytest.raises(InputError, match="map.ply: is a folder, not a file"):
        read_contour_map(tmp_path / "map.ply")
    with pytest.raises(InputError, match="gt.txt: is a folder, not a file"):
        read_table(tmp_path / "gt.txt", 8)


_BOMB = ", ".join(["&a [x, x, x, x, x, x, x, x, x]"] + [f"&{chr(98 + i)} [" + ", ".join([f"*{chr(97 + i)}"] * 9) + "]" for i in range(8)])


@pytest.mark.parametrize("text, message", [
    # A 9-level YAML alias chain under a known key: printing the value in the message never ended.
    (f"rate_hz: [{_BOMB}]\n", "rate_hz: expected a number, got [['x', 'x', 'x', 'x', ...], [[...]"),
    (f"mode: [{_BOMB}]\n", "mode: expected one of stpe, stpe+filter, full, got [["),
    (f"noise_filter: {{enabled: [{_BOMB}]}}\n", "noise_filter.enabled: expected true/false, got [["),
    ("rate_hz: " + "x" * 100_000 + "\n", "rate_hz: expected a number, got 'xxxxxxxx"),
    # Sorting unknown keys 1 and "foo" was a TypeError traceback.
    ("1: a\nfoo: b\n", "1: unknown setting"),
    ("mode: 3\n", "mode: expected one of stpe, stpe+filter, full, got 3"),
])
def test_config_values_of_any_shape_give_a_short_message_at_once(tmp_path, text, message):
    import time

    path = tmp_path / "cfg.yaml"
    path.write_text(text)
    t0 = time.perf_counter()
    with pytest.raises(InputError) as info:
        read_config(TrackerConfig, path)
    assert time.perf_counter() - t0 < 1.0
    msg = _one_line(info, path)
    assert message in msg and len(msg) < len(str(path)) + 500  # the known settings are listed for an unknown one


@pytest.mark.parametrize("value, message", [
    ("abc", "viewpoint: expected a list of 3 values, got 'abc'"),
    ("true", "viewpoint: expected a list of 3 values, got True"),
    ("[1, 2]", "viewpoint: expected 3 values, got 2"),
    ("[a, b, c]", "viewpoint: expected a number, got 'a'"),
    ("[[1], 2, 3]", "viewpoint: expected a number, got [1]"),
    ("[.nan, 0, 0]", "viewpoint: expected a finite number, got nan"),  # named the field but not the file
])
def test_a_tuple_setting_is_checked_like_a_number_naming_the_file(tmp_path, value, message):
    # MapBuildConfig.viewpoint (x y z) was taken as given: "abc" or [1, 2] ended in tracebacks inside build-map.
    from evpose.mapping.build import MapBuildConfig

    path = tmp_path / "build.yaml"
    path.write_text(f"viewpoint: {value}\n")
    with pytest.raises(InputError) as info:
        read_config(MapBuildConfig, path)
    assert message in _one_line(info, path)


def test_a_tuple_setting_and_null_read_as_given(tmp_path):
    from evpose.mapping.build import MapBuildConfig

    path = tmp_path / "build.yaml"
    path.write_text("viewpoint: [1, 2.5, -3]\n")
    assert read_config(MapBuildConfig, path).viewpoint == (1.0, 2.5, -3.0)
    path.write_text("viewpoint: null\n")
    assert read_config(MapBuildConfig, path).viewpoint is None
