"""Lesson bookmarks in a real headless Chromium: save the moment on screen, move away (another recording, stage and
layout), go back to it; rename, move up and delete (only once confirmed) from the page, and reload a hand edit."""

import dataclasses

import pytest

from app.player import PlayerConfig
from app.tracker_engine import TrackerEngine
from browser_session import running_viewer, wait_for

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def viewer(tmp_path_factory, squares_scene):
    from app.layouts import LAYOUT_DIR
    from app_scenes import sweeping_bar_recording, write_squares_root
    from evpose.io.h5 import write_recording_h5

    root = write_squares_root(tmp_path_factory.mktemp("data"), squares_scene)
    write_recording_h5(root / "bar.h5", sweeping_bar_recording())
    layouts = tmp_path_factory.mktemp("layouts")  # the bookmarks file goes beside these
    for f in LAYOUT_DIR.glob("*.json"):
        (layouts / f.name).write_text(f.read_text())
    with running_viewer(tmp_path_factory, root, layout_dir=layouts, warm_up=False, player=PlayerConfig(prefetch=False)) as app:
        yield app


def control_row(page, label):
    """The row of a labelled control (as in test_server_browser.py: viser's text boxes are not <label>-associated)."""
    lab = page.locator("label", has_text=label).filter(has_text=label).first
    return lab.locator("xpath=ancestor::div[contains(@class,'mantine-Flex-root')][1]")


def _option(viewer, name):
    return next(o for o in viewer.rec_dropdown.options if o.endswith("/" + name))


def test_a_saved_bookmark_brings_back_its_recording_step_stage_and_layout(page, viewer):
    squares, bar = _option(viewer, "squares.h5"), _option(viewer, "bar.h5")
    assert viewer.select(squares)
    wait_for(lambda: isinstance(viewer.player.engine, TrackerEngine) and viewer.last_frame is not None
             and viewer._shown_label == squares, timeout=90, what="squares opened")
    viewer.apply_layout_name("teaching")
    viewer.player.seek(viewer.player.engine.t_start_us + 200_000)
    wait_for(lambda: viewer.player.wait_idle() and viewer.last_frame.index > 5, what="a step 0.2 s in")
    shown = viewer.last_frame.index
    viewer.player.step_forward()  # off the grid of kept frames a seek may snap to: going back must not snap
    wait_for(lambda: viewer.player.wait_idle() and viewer.last_frame.index == shown + 1, what="one step on")
    viewer.stage_dropdown.value = "registration"
    step, t_us = viewer.last_frame.index, viewer.last_frame.t_us

    page.get_by_text("Bookmarks", exact=True).first.click()  # the folder opens
    control_row(page, "bookmark title").locator("input").fill("registration at 0.2 s")
    wait_for(lambda: viewer.bookmark_gui.title_box.value == "registration at 0.2 s", what="title typed")
    page.get_by_role("button", name="save this moment").click()
    wait_for(lambda: len(viewer.bookmark_gui.bookmarks) == 1, what="bookmark saved")
    saved = viewer.bookmark_gui.bookmarks[0]
    assert (saved.recording, saved.step, saved.stage, saved.layout) == (squares, step, "registration", "teaching")
    assert viewer.cfg.bookmarks_path().is_file()
    page.get_by_text("saved 1. registration at 0.2 s", exact=False).first.wait_for(timeout=10_000)

    # Away: another recording, layout and stage.
    assert viewer.select(bar)
    wait_for(lambda: viewer._shown_label == bar and viewer.last_frame is not None and viewer.last_frame.index == 0,
             timeout=60, what="bar opened")
    viewer.apply_layout_name("debug")
    viewer.stage_dropdown.value = "events"

    page.get_by_role("button", name="go to").click()
    wait_for(lambda: viewer._shown_label == squares and viewer.last_frame is not None and viewer.last_frame.index == step,
             timeout=90, what="back at the bookmarked step",
             detail=lambda: f"{viewer._shown_label} step {viewer.last_frame and viewer.last_frame.index}")
    assert viewer.last_frame.t_us == t_us
    assert viewer.stage.value == "registration" and viewer.layout.name == "teaching"
    page.locator("h3", has_text="registration").first.wait_for(timeout=10_000)  # the teaching panel shows that stage


def test_bookmarks_are_renamed_reordered_and_deleted_only_once_confirmed(page, viewer):
    from app.bookmarks import load_bookmarks, save_bookmarks

    gui, path = viewer.bookmark_gui, viewer.cfg.bookmarks_path()
    wait_for(lambda: viewer.last_frame is not None and viewer.player.wait_idle(), timeout=60, what="a step shown")
    if not page.get_by_role("button", name="save this moment").is_visible():
        page.get_by_text("Bookmarks", exact=True).first.click()
    before = [b.title for b in load_bookmarks(path)]
    title = control_row(page, "bookmark title").locator("input")
    title.fill("second")
    wait_for(lambda: gui.title_box.value == "second", what="title typed")
    page.get_by_role("button", name="save this moment").click()
    wait_for(lambda: [b.title for b in load_bookmarks(path)] == before + ["second"], what="second saved")

    title.fill("the second, renamed")
    wait_for(lambda: gui.title_box.value == "the second, renamed", what="new title typed")
    page.get_by_role("button", name="rename", exact=True).click()
    wait_for(lambda: [b.title for b in load_bookmarks(path)] == before + ["the second, renamed"], what="renamed")
    page.get_by_role("button", name="move up").click()
    wait_for(lambda: [b.title for b in load_bookmarks(path)] == ["the second, renamed"] + before, what="moved up")
    page.get_by_text("'the second, renamed' is number 1 of").first.wait_for(timeout=10_000)

    page.get_by_role("button", name="delete", exact=True).click()  # asks first: nothing is gone yet
    page.get_by_role("button", name="yes, delete").wait_for(timeout=10_000)
    page.get_by_text("delete 1. the second, renamed").first.wait_for(timeout=10_000)
    assert [b.title for b in load_bookmarks(path)] == ["the second, renamed"] + before
    page.get_by_role("button", name="no, keep it").click()
    page.get_by_role("button", name="yes, delete").wait_for(state="hidden", timeout=10_000)
    assert [b.title for b in load_bookmarks(path)] == ["the second, renamed"] + before

    page.get_by_role("button", name="delete", exact=True).click()
    page.get_by_role("button", name="yes, delete").click()
    wait_for(lambda: [b.title for b in load_bookmarks(path)] == before, what="deleted once confirmed")
    page.get_by_role("button", name="yes, delete").wait_for(state="hidden", timeout=10_000)
    page.get_by_text("deleted 'the second, renamed'").first.wait_for(timeout=10_000)

    # Edited by hand (a teacher's text editor): "reload" lists it without a restart.
    marks = load_bookmarks(path)
    save_bookmarks(marks + [dataclasses.replace(marks[0], title="typed by hand")], path)
    page.get_by_role("button", name="reload", exact=True).click()
    wait_for(lambda: [b.title for b in gui.bookmarks] == before + ["typed by hand"], what="the hand edit read")
    page.get_by_text(f"read {len(before) + 1} bookmarks from").first.wait_for(timeout=10_000)
