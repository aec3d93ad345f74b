"""TrackerConfig: YAML/JSON round trip, unknown keys and bad values are one-line input errors, slider metadata."""

import dataclasses
import typing

import pytest

from evpose.errors import InputError
from evpose.tracker.config import TrackerConfig, TrackerMode, config_from_dict, config_to_dict, load_config, save_config
from evpose.tracker.registration import RobustLoss


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_config_round_trips_through_files(tmp_path, suffix):
    cfg = TrackerConfig(mode=TrackerMode.STPE, rate_hz=300.0)
    cfg.registration.robust_loss = RobustLoss.CAUCHY
    cfg.time_surface.eta_ms = 12.5
    save_config(cfg, tmp_path / f"c{suffix}")
    assert load_config(tmp_path / f"c{suffix}") == cfg


def test_partial_config_keeps_defaults(tmp_path):
    (tmp_path / "c.yaml").write_text("noise_filter:\n  window_us: 2000\n")
    cfg = load_config(tmp_path / "c.yaml")
    assert cfg.noise_filter.window_us == 2000 and cfg.rate_hz == TrackerConfig().rate_hz


def test_unknown_key_is_an_input_error_naming_it(tmp_path):
    (tmp_path / "c.yaml").write_text("registration:\n  max_itertions: 3\n")
    with pytest.raises(InputError, match="registration.max_itertions"):
        load_config(tmp_path / "c.yaml")


def test_bad_value_is_an_input_error(tmp_path):
    (tmp_path / "c.json").write_text('{"mode": "warp"}')
    with pytest.raises(InputError, match="mode"):
        load_config(tmp_path / "c.json")
    with pytest.raises(InputError, match="rate_hz"):
        config_from_dict(TrackerConfig, {"rate_hz": "fast"})
    (tmp_path / "broken.yaml").write_text("a: [1,\n")
    with pytest.raises(InputError, match="YAML"):
        load_config(tmp_path / "broken.yaml")


@pytest.mark.parametrize("text, message", [
    ("noise_filter:\n  window_us: -5\n", r"noise_filter.window_us: -5 is outside the allowed range 100..100000 us"),
    ("time_surface:\n  eta_ms: .nan\n", r"time_surface.eta_ms: expected a finite number"),
    ("rate_hz: 1.0e+9\n", r"rate_hz: 1000000000.0 is outside the allowed range"),
])
def test_numbers_outside_their_declared_range_are_input_errors(tmp_path, text, message):
    (tmp_path / "c.yaml").write_text(text)
    with pytest.raises(InputError, match=message):
        load_config(tmp_path / "c.yaml")


def test_every_default_lies_inside_its_declared_range():
    def walk(cfg):
        for f in dataclasses.fields(cfg):
            v = getattr(cfg, f.name)
            if dataclasses.is_dataclass(v):
                yield from walk(v)
            elif "min" in f.metadata and not isinstance(v, bool):
                yield f.name, f.metadata["min"] <= v <= f.metadata["max"]
    checked = dict(walk(TrackerConfig()))
    assert checked and all(checked.values()), [k for k, ok in checked.items() if not ok]


def test_every_numeric_field_has_slider_metadata_and_a_docstring_unit():
    def leaves(cls):
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            t = hints[f.name]
            if dataclasses.is_dataclass(t):
                yield from leaves(t)
            elif t in (int, float):
                yield f

    fields = list(leaves(TrackerConfig))
    assert len(fields) > 15
    for f in fields:
        assert {"min", "max", "step", "unit"} <= set(f.metadata), f.name


def test_config_dict_is_plain():
    d = config_to_dict(TrackerConfig())
    assert d["mode"] == "full" and isinstance(d["registration"]["robust_loss"], str)
