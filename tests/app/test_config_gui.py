"""The parameter GUI is generated from the config dataclasses; files round-trip."""

import dataclasses
import enum

import pytest
import viser

from app.config_gui import ConfigGui, field_specs, from_plain, get_path, load_config_file, replace_path, save_config_file, to_plain
from app.slam_engine import SlamViewConfig
from evpose.errors import InputError
from evpose.tracker.config import TrackerConfig


class Colour(str, enum.Enum):
    RED = "red"
    BLUE = "blue"


@dataclasses.dataclass
class Inner:
    gain: float = dataclasses.field(default=2.0, metadata={"min": 0.0, "max": 10.0, "step": 0.5, "unit": "x"})
    """Gain, ratio."""
    count: int = 3
    """How many, items."""


@dataclasses.dataclass
class Outer:
    colour: Colour = Colour.RED
    """Colour of things."""
    enabled: bool = True
    inner: Inner = dataclasses.field(default_factory=Inner)


def test_every_tracker_field_gets_a_spec_with_docs():
    specs = field_specs(TrackerConfig())
    names = {s.name for s in specs}
    assert {"rate_hz", "time_surface.eta_ms", "registration.robust_scale", "noise_filter.window_us"} <= names
    flat = len([1 for _ in specs])
    assert flat == len(names)
    assert all(s.doc for s in specs), [s.name for s in specs if not s.doc]


def test_widgets_match_field_types_and_edits_produce_new_configs():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        seen = []
        gui = ConfigGui(server.gui, Outer(), seen.append)
        h = gui.handles
        assert type(h[("colour",)]).__name__ == "GuiDropdownHandle"
        assert type(h[("enabled",)]).__name__ == "GuiCheckboxHandle"
        assert type(h[("inner", "gain")]).__name__ == "GuiSliderHandle"
        assert type(h[("inner", "count")]).__name__ == "GuiNumberHandle"
        assert h[("inner", "gain")].label == "gain [x]"
        h[("inner", "gain")].value = 4.5
        h[("colour",)].value = "blue"
        assert seen[-1] == Outer(colour=Colour.BLUE, inner=Inner(gain=4.5))
        gui.set_config(Outer())  # shows values without firing a change
        assert len(seen) == 2 and h[("inner", "gain")].value == 2.0
        gui.reset()
        assert seen[-1] == Outer()
    finally:
        server.stop()


def test_two_controls_moved_at_once_from_two_tabs_both_reach_the_config(monkeypatch):
    import threading
    import time

    import app.config_gui as config_gui

    copy = config_gui.replace_path

    def slow_copy(*args):  # widens the window between reading the config and writing it back
        time.sleep(0.05)
        return copy(*args)

    monkeypatch.setattr(config_gui, "replace_path", slow_copy)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        seen = []
        gui = ConfigGui(server.gui, Outer(), seen.append)
        gain, colour = gui.handles[("inner", "gain")], gui.handles[("colour",)]
        gain._impl.value, colour._impl.value = 4.5, "blue"  # as viser sets them before calling back, on its thread pool
        moves = [threading.Thread(target=h._impl.update_cb[0], args=(None,)) for h in (gain, colour)]
        for t in moves:
            t.start()
        for t in moves:
            t.join()
        assert gui.config == seen[-1] == Outer(colour=Colour.BLUE, inner=Inner(gain=4.5))
    finally:
        server.stop()


def test_integer_sliders_offer_their_default_and_odd_kernel_sizes_only_odd_values():
    # A browser slider offers min + k * step: the TDF blur (min 0, step 2) offered 0, 2, 4... and read 4 while the
    # field blurred with 5 (even kernels are rounded up), and its default 3 could not be dragged back to.
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        gui = ConfigGui(server.gui, TrackerConfig(), lambda cfg: None)
        blur = gui.handles[("distance_field", "blur_px")]
        assert blur.min == 1 and blur.step == 2 and (blur.max - blur.min) % 2 == 0
        for spec in field_specs(TrackerConfig()):
            h = gui.handles[spec.path]
            if isinstance(h, viser.GuiSliderHandle) and type(spec.default) is int and "zero" not in spec.metadata:
                assert (spec.default - h.min) % h.step == 0 and h.min >= spec.metadata["min"], spec.name
    finally:
        server.stop()


@pytest.mark.parametrize("config, path, zero", [
    (TrackerConfig(), ("distance_field", "coarse_blur_px"), "off"),
    (SlamViewConfig(), ("slam", "features", "klt_upsample_window_px"), "automatic"),
])
def test_a_kernel_size_whose_0_means_off_or_automatic_offers_odd_sizes_and_a_checkbox_for_the_0(config, path, zero):
    # The coarse TDF blur's slider (0 = off, step 2) offered 2, 4...: 2 shown, 3 used. SLAM's fine KLT window (0 =
    # automatic) started at 1 and its 0 could be set in a configuration file only.
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        seen = []
        gui = ConfigGui(server.gui, config, seen.append)
        slider, box = gui.handles[path], gui.zero_boxes[path]
        assert slider.min == 1 and slider.step == 2 and (slider.max - slider.min) % 2 == 0
        assert box.label.endswith(zero) and box.value == (get_path(config, path) == 0) == slider.disabled
        box.value = True
        assert get_path(gui.config, path) == 0 and slider.disabled
        box.value = False
        assert get_path(gui.config, path) == get_path(seen[-1], path) == slider.value and slider.value % 2 == 1 and not slider.disabled
        slider.value = 9
        assert get_path(gui.config, path) == 9
        gui.set_config(replace_path(config, path, 0))  # a loaded file's 0: the box shows it, the slider keeps 9
        assert box.value and slider.disabled and slider.value == 9 and get_path(gui.config, path) == 0
        gui.reset()
        assert box.value == (get_path(config, path) == 0) and get_path(gui.config, path) == get_path(config, path)
    finally:
        server.stop()


def test_a_value_typed_past_a_sliders_end_is_shown_and_used_at_that_end():
    # The slider's box took 5000 for a 10-1000 Hz rate: shown and run with, a value a config file is refused for.
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        seen = []
        gui = ConfigGui(server.gui, TrackerConfig(), seen.append)
        rate, blur = gui.handles[("rate_hz",)], gui.handles[("distance_field", "blur_px")]
        rate.value = 5000.0
        blur.value = -3
        assert rate.value == rate.max == gui.config.rate_hz == seen[-1].rate_hz
        assert blur.value == blur.min == gui.config.distance_field.blur_px
        unbounded = ConfigGui(server.gui, Outer(), seen.append)  # a number box without min/max takes any value
        unbounded.handles[("inner", "count")].value = -40
        assert unbounded.config.inner.count == -40
    finally:
        server.stop()


def test_config_files_round_trip_and_reject_unknown_keys(tmp_path):
    cfg = dataclasses.replace(TrackerConfig(), rate_hz=123.0)
    save_config_file(cfg, tmp_path / "c.yaml")
    assert load_config_file(TrackerConfig, tmp_path / "c.yaml") == cfg
    assert from_plain(Outer, to_plain(Outer(colour=Colour.BLUE))) == Outer(colour=Colour.BLUE)
    with pytest.raises(InputError, match="inner.nope"):
        from_plain(Outer, {"inner": {"nope": 1}})
    with pytest.raises(InputError, match="inner.gain"):
        from_plain(Outer, {"inner": {"gain": "lots"}})


def test_a_control_whose_name_ends_in_its_unit_says_the_unit_once():
    from app.slam_engine import SlamViewConfig
    from evpose.tracker.config import TrackerConfig

    labels = {s.name: s.label for c in (TrackerConfig(), SlamViewConfig()) for s in field_specs(c)}
    assert labels["rate_hz"] == "rate [Hz]"
    assert labels["step_us"] == "step [us]"
    with_unit = [lab for lab in labels.values() if lab.endswith("]")]
    assert len(with_unit) > 60
    assert not [lab for lab in with_unit if lab.split(" [")[0].split(" ")[-1].lower() == lab.rsplit("[", 1)[-1][:-1].lower()]
