"""Slider-key shortcuts: a key press that moved a focused slider does not also step the player."""

import threading
import time

from app.hotkeys import SliderKeyGuard


def test_an_arrow_shortcut_runs_when_no_slider_moved():
    guard = SliderKeyGuard(window_s=0.05)
    ran = []
    assert guard.run(lambda: ran.append(1)).result(5)
    assert ran == [1]


def test_an_arrow_shortcut_that_came_with_a_slider_move_is_dropped_whichever_arrives_first():
    guard = SliderKeyGuard(window_s=0.5)  # wide: the timer below must land inside it on a loaded machine
    ran = []
    guard.slider_moved()  # the slider's update first (the usual order in the browser)
    assert not guard.run(lambda: ran.append("before")).result(5)
    # The slider's update held back by the client's 50 ms throttle: it lands while the shortcut waits.
    t = threading.Timer(0.04, guard.slider_moved)
    t.start()
    assert not guard.run(lambda: ran.append("after")).result(5)
    t.join()
    assert ran == []


def test_a_slider_moved_long_before_does_not_block_a_later_shortcut():
    guard = SliderKeyGuard(window_s=0.05)
    guard.slider_moved(at=time.monotonic() - 1.0)
    ran = []
    assert guard.run(lambda: ran.append(1)).result(5)
    assert ran == [1]


class _Handle:
    def __init__(self):
        self.callbacks = []

    def on_update(self, cb):
        self.callbacks.append(cb)


class _Event:
    def __init__(self, client):
        self.client = client


def test_only_browser_moves_of_watched_sliders_count():
    guard = SliderKeyGuard(window_s=0.05)
    h = _Handle()
    guard.watch([h])
    h.callbacks[0](_Event(client=None))  # the server writing the slider (e.g. the time slider while playing)
    assert guard.run(lambda: None).result(5)
    h.callbacks[0](_Event(client=object()))
    assert not guard.run(lambda: None).result(5)
