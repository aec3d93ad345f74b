"""The Parameters panel's buttons in a real headless Chromium: what "save", "reset" and "load" did stays said above the
controls after the tracker is rebuilt (its note replaced "loaded ..." within a second, so a load seemed to do nothing),
and the controls and the engine take the loaded values."""

import pytest

from app.player import PlayerConfig
from app.tracker_engine import TrackerEngine
from browser_session import running_viewer, wait_for

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def viewer(tmp_path_factory, squares_scene):
    from app_scenes import write_squares_root

    root = write_squares_root(tmp_path_factory.mktemp("data"), squares_scene)
    with running_viewer(tmp_path_factory, root, warm_up=False, player=PlayerConfig(prefetch=False)) as app:
        yield app


def _box(page, label):
    """The typed-in box of a labelled control (viser's boxes are not <label>-associated)."""
    return page.locator("label", has_text=label).first.locator(
        "xpath=ancestor::div[contains(@class,'mantine-Flex-root')][1]").locator("input").last


def _rebuilt(viewer, rate_hz):
    return viewer.player.wait_idle(5) and viewer.player.engine.config.rate_hz == rate_hz


def test_save_reset_and_load_say_what_they_did_after_the_tracker_is_rebuilt(page, viewer):
    wait_for(lambda: isinstance(viewer.player.engine, TrackerEngine) and viewer.last_frame is not None, timeout=90,
             what="squares opened with its map")
    rate = _box(page, "rate [Hz]")
    rate.fill("150")
    rate.press("Enter")
    wait_for(lambda: _rebuilt(viewer, 150.0), what="the tracker at 150 Hz")
    _box(page, "config file").fill("lesson.yaml")
    wait_for(lambda: viewer.config_path.value == "lesson.yaml", what="file name typed")
    page.get_by_role("button", name="save", exact=True).click()
    wait_for(lambda: (viewer.cfg.export_dir / "lesson.yaml").is_file(), what="lesson.yaml saved")
    assert "rate_hz: 150" in (viewer.cfg.export_dir / "lesson.yaml").read_text()

    page.get_by_role("button", name="reset", exact=True).click()
    wait_for(lambda: _rebuilt(viewer, 200.0), what="the tracker back at its default 200 Hz")
    wait_for(lambda: rate.input_value() == "200", what="the rate box at 200", detail=rate.input_value)
    page.get_by_text("configuration reset to defaults").first.wait_for(timeout=10_000)

    page.get_by_role("button", name="load", exact=True).click()
    wait_for(lambda: _rebuilt(viewer, 150.0), what="the tracker at the loaded 150 Hz")
    wait_for(lambda: rate.input_value() == "150", what="the rate box at 150", detail=rate.input_value)
    # After the rebuild (whose note came after it and replaced it): still said, above the engine's note.
    page.get_by_text("loaded ").first.wait_for(timeout=10_000)
    assert viewer.param_info.content.startswith(f"loaded `{(viewer.cfg.export_dir / 'lesson.yaml').resolve()}`")
    assert "a change re-runs it" in viewer.param_info.content

    rate.fill("180")  # a control moved: what the button did is past
    rate.press("Enter")
    wait_for(lambda: _rebuilt(viewer, 180.0), what="the tracker at 180 Hz")
    wait_for(lambda: not viewer.param_info.content.startswith("loaded"), what="the load's line gone",
             detail=lambda: viewer.param_info.content)


@pytest.mark.parametrize("typed", ["", "abc", "inf"])
def test_a_number_box_left_holding_no_number_shows_its_value_again_and_nothing_is_rerun(page, viewer, typed):
    # The box kept showing the typed text (empty, "abc") while the player and the tracker ran with the old value.
    wait_for(lambda: isinstance(viewer.player.engine, TrackerEngine), timeout=90, what="squares opened with its map")
    for label in ("rate [Hz]", "speed [x]"):
        box = _box(page, label)
        shown = box.input_value()
        assert shown not in ("", typed)
        applies = viewer.player.config_applies
        box.fill(typed)
        box.press("Tab")
        wait_for(lambda: box.input_value() == shown, timeout=5, what=f"{label} box showing {shown} again", detail=box.input_value)
        assert viewer.player.config_applies == applies
