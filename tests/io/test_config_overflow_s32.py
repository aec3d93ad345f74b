"""A number too large for a float, in a config file or a flag, is a one-line error (session 32's fuzzing)."""

from __future__ import annotations

import pytest

from evpose.errors import InputError
from evpose.io.config_file import read_config

HUGE = "9" * 400  # YAML and JSON read it as an exact integer; float() of it is an OverflowError


@pytest.mark.parametrize("suffix, text", [(".yaml", f"event_registration:\n  lead_reference_pixel_mrad: {HUGE}\n"),
                                          (".json", f'{{"event_registration": {{"lead_reference_pixel_mrad": {HUGE}}}}}')])
def test_a_float_setting_given_an_integer_beyond_any_float_is_named_in_one_line(tmp_path, suffix, text):
    from evpose.tracker.config import TrackerConfig

    path = tmp_path / f"cfg{suffix}"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        read_config(TrackerConfig, path)
    message = str(info.value)
    assert message.startswith(f"{path}: event_registration.lead_reference_pixel_mrad: expected a finite number, got 999")
    assert "\n" not in message and len(message) < len(str(path)) + 200


def test_a_tuple_setting_given_such_an_integer_is_named_too(tmp_path):
    from evpose.mapping.build import MapBuildConfig

    path = tmp_path / "map.yaml"
    path.write_text(f"viewpoint: [0, {HUGE}, 1]\n")
    with pytest.raises(InputError, match="viewpoint: expected a finite number"):
        read_config(MapBuildConfig, path)


@pytest.mark.parametrize("flag", ["--k", "--min-region"])
def test_an_integer_flag_beyond_any_float_exits_2_with_one_line(tmp_path, capsys, flag):
    # check_config's range test ran math.isfinite on it: "OverflowError: int too large to convert to float", exit 1.
    from evpose.cli.main import run

    cloud = tmp_path / "cloud.ply"
    cloud.write_bytes(b"not read: the flag is refused first")
    assert run(["build-map", str(cloud), "--out", str(tmp_path / "m.ply"), flag, HUGE]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("evpose build-map: error: ") and "outside the allowed range" in err
    assert "999...999" in err  # shown cut, not 400 digits


def test_integers_inside_the_range_still_pass(tmp_path):
    from evpose.mapping.build import MapBuildConfig

    path = tmp_path / "map.yaml"
    path.write_text("k_neighbours: 100\nmin_region_points: 3\n")
    cfg = read_config(MapBuildConfig, path)
    assert (cfg.k_neighbours, cfg.min_region_points) == (100, 3)
