"""Opening a recording in a real headless Chromium while the player is busy, and a map nothing registers against in
a recording shorter than ``--acquire-s``: the status line says what is going on in both cases."""

import dataclasses
import threading

import numpy as np
import pytest

from app.player import PlayerConfig
from app.server import OPENING
from browser_session import choose, running_viewer, wait_for

pytestmark = pytest.mark.browser


def wrong_map(cmap):
    """A patch of edgeless ground under the start pose: in view, but not this scene's map (as in test_warm_up.py)."""
    n = 300
    patch = np.c_[np.random.default_rng(0).uniform(-0.04, 0.04, (n, 2)), np.full(n, cmap.points[:, 2].mean())]
    return dataclasses.replace(cmap, points=patch, **{k: getattr(cmap, k)[:n] for k in
                                                      ("edge_normal", "plane_normal", "region_id", "curvature", "brightness_sign")})


@pytest.fixture(scope="module")
def viewer(tmp_path_factory, squares_scene):
    from app_scenes import map_scene, write_squares_root
    from evpose.io.h5 import write_recording_h5
    from evpose.io.map_ply import write_contour_map

    cmap = squares_scene[1]
    root = write_squares_root(tmp_path_factory.mktemp("data"), squares_scene)
    # 0.2 s, none of whose 33 updates registers against the patch (a 0.5 s one registers from update 44 on)
    short = map_scene(duration_s=0.2)[0]
    write_recording_h5(root / "wrong.h5", dataclasses.replace(short, metadata={"scene": "wrong"}))
    write_contour_map(root / "wrong_map.ply", wrong_map(cmap))
    with running_viewer(tmp_path_factory, root, warm_up=False, player=PlayerConfig(prefetch=True)) as app:
        yield app


def _option(viewer, name):
    return next(o for o in viewer.rec_dropdown.options if o.endswith("/" + name))


def test_opening_a_recording_while_the_player_computes_says_it_waits_then_opens_it(page, viewer):
    wait_for(lambda: viewer.last_frame is not None and viewer.rec_dropdown.value.endswith("/squares.h5"), timeout=90,
             what="squares opened")
    viewer.player.wait_idle()
    gate = threading.Event()
    viewer.player.call(lambda _engine: gate.wait(30))  # the worker busy as with a cold first step
    wait_for(lambda: viewer.player.computing, what="the player busy")
    squares = _option(viewer, "squares.h5")
    try:
        choose(page, "recording", _option(viewer, "wrong.h5"))
        said = f"waiting for the step of {squares} being computed to finish"
        page.get_by_text(said).first.wait_for(timeout=20_000)
        assert "computing its first step" not in viewer.status.content
        assert f"still those of `{squares}`" in viewer.param_info.content  # the panel is not the new recording's yet
    finally:
        gate.set()
    wait_for(lambda: viewer.last_frame is not None and viewer.recording.metadata == {"scene": "wrong"}
             and not viewer.status.content.startswith(OPENING), timeout=30, what="wrong.h5 opened",
             detail=lambda: viewer.status.content)
    assert "still those" not in viewer.param_info.content


def test_a_map_nothing_registers_against_in_a_recording_shorter_than_acquire_s_is_warned_once_computed(page, viewer):
    wait_for(lambda: viewer.last_frame is not None, timeout=90, what="a recording open")
    if viewer.recording.metadata != {"scene": "wrong"}:  # run alone
        choose(page, "recording", _option(viewer, "wrong.h5"))
        wait_for(lambda: viewer.recording.metadata == {"scene": "wrong"}, timeout=60, what="wrong.h5 open")
    assert viewer.map_dropdown.value.endswith("/wrong_map.ply")
    engine = viewer.player.engine
    wait_for(lambda: engine.ready_steps >= engine.n_steps, timeout=60, what="every step computed")
    page.get_by_text("no update registered against this map in the whole recording").first.wait_for(timeout=20_000)
    choose(page, "recording", _option(viewer, "squares.h5"))  # its own map registers: no warning
    wait_for(lambda: viewer.player.engine is not engine and viewer.player.engine.ready_steps >= viewer.player.engine.n_steps,
             timeout=60, what="squares computed")
    viewer.player.wait_idle()
    viewer._on_progress(viewer.player.engine)
    assert "registered against this map" not in viewer.status.content
