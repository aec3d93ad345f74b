"""Switches made while paused, in a real headless Chromium: another viewer mode or map goes on at the moment shown (the
same recording was back at its first step, the time slider at 0 with no word why), a new speed is said at once, and a
time typed past the end is brought to the end in the box at once."""

import threading

import pytest

from app.engine import EventsOnlyEngine
from app.player import PlayerConfig
from app.slam_engine import SlamEngine
from app.tracker_engine import TrackerEngine
from browser_session import choose, running_viewer, wait_for

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def viewer(tmp_path_factory, squares_scene):
    from app_scenes import write_squares_root

    root = write_squares_root(tmp_path_factory.mktemp("data"), squares_scene)
    with running_viewer(tmp_path_factory, root, warm_up=False, player=PlayerConfig(prefetch=False)) as app:
        yield app


def _at(viewer, kind, offset_us):
    """The engine is of ``kind`` and the step drawn is at ``offset_us`` from the start."""
    p, f = viewer.player, viewer.last_frame
    return (isinstance(p.engine, kind) and f is not None and f.t_us - p.engine.t_start_us == offset_us
            and p.wait_idle(5))


def test_switching_viewer_mode_and_map_goes_on_at_the_time_shown(page, viewer):
    wait_for(lambda: isinstance(viewer.player.engine, TrackerEngine) and viewer.last_frame is not None, timeout=90,
             what="squares opened with its map")
    viewer.player.seek(viewer.player.engine.t_start_us + 200_000, exact=True)
    wait_for(lambda: _at(viewer, TrackerEngine, 200_000), what="the tracker at 0.2 s")
    time_box = page.locator("label", has_text="time [s]").first.locator("xpath=ancestor::div[contains(@class,'mantine-Flex-root')][1]").locator("input").last

    choose(page, "viewer mode", "slam")
    wait_for(lambda: _at(viewer, SlamEngine, 200_000), timeout=60, what="SLAM at 0.2 s",
             detail=lambda: f"{type(viewer.player.engine).__name__} at {viewer.last_frame and viewer.last_frame.t_us}")
    assert viewer.last_frame.slam is not None
    wait_for(lambda: time_box.input_value() == "0.2", what="the page's time box at 0.2", detail=time_box.input_value)

    choose(page, "viewer mode", "tracking")
    wait_for(lambda: _at(viewer, TrackerEngine, 200_000), timeout=60, what="the tracker at 0.2 s again")
    choose(page, "map", "(no map: events only)")
    wait_for(lambda: _at(viewer, EventsOnlyEngine, 200_000), timeout=60, what="events only at 0.2 s")
    wait_for(lambda: time_box.input_value() == "0.2", what="the page's time box at 0.2", detail=time_box.input_value)
    page.get_by_text("t = 0.200 s").first.wait_for(timeout=10_000)  # the status line says the same moment


def test_a_speed_set_while_paused_is_said_in_the_status_line_at_once(page, viewer):
    wait_for(lambda: viewer.last_frame is not None and viewer.player.wait_idle(5), timeout=60, what="a step shown")
    assert viewer.player.state.value == "paused"
    box = page.locator("label", has_text="speed [x]").first.locator(
        "xpath=ancestor::div[contains(@class,'mantine-Flex-root')][1]").locator("input").last
    box.fill("3")
    box.press("Enter")
    wait_for(lambda: viewer.player.speed == 3.0, what="the player at 3x")
    # Nothing is drawn while paused: the line kept "paused at 1.0x" until play.
    page.get_by_text("paused at 3.0x").first.wait_for(timeout=10_000)
    box.fill("1")
    box.press("Enter")
    page.get_by_text("paused at 1.0x").first.wait_for(timeout=10_000)


def test_a_time_typed_past_the_end_is_brought_to_the_end_in_the_box(page, viewer):
    wait_for(lambda: viewer.last_frame is not None and viewer.player.wait_idle(5), timeout=60, what="a step shown")
    box = page.locator("label", has_text="time [s]").first.locator(
        "xpath=ancestor::div[contains(@class,'mantine-Flex-root')][1]").locator("input").last
    end = viewer.time_slider.max
    gate = threading.Event()
    viewer.player.call(lambda _engine: gate.wait(30))  # the player busy, as SLAM computing up to the end (demo: 20 s)
    try:
        box.fill("100")
        box.press("Enter")
        # At once, not once the player has drawn the last step.
        wait_for(lambda: box.input_value() == f"{end:g}", timeout=10, what=f"the box at {end:g}", detail=box.input_value)
    finally:
        gate.set()
    wait_for(lambda: viewer.player.wait_idle(5) and viewer.player.engine.is_last(viewer.last_frame), what="the last step shown")
    box.fill("0")
    box.press("Enter")
    wait_for(lambda: viewer.player.wait_idle(5) and viewer.last_frame.index == 0, what="back at the first step")
