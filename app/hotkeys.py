"""Keyboard shortcuts, and the guard that keeps a key meant for a slider from also stepping the player.

viser's browser client fires a shortcut for every key press outside text inputs, but a
focused slider thumb is not a text input: it moves with the arrow keys (and Home/End) and
the same key press also fires the shortcut bound to it. Measured in Chromium before this
guard: one ArrowLeft on the focused speed slider set the speed 1.1 -> 1.0x *and* stepped
the player back one step; six ArrowRight on a parameter slider stepped the shown step
392 -> 400 while the tracker re-ran. A slider is focused by clicking it, so the next arrow
key after a drag did this too.

The browser reports neither the key nor the focus, only the two results: the slider's new
value and the shortcut. :class:`SliderKeyGuard` therefore holds an arrow/Home shortcut for
``window_s`` and drops it when a slider moved by a browser within ``window_s`` of it (the
client sends GUI values at most every 50 ms, so the slider's update may come just after the
shortcut). Space, which no slider uses, acts at once.

Limit: the client sends a press's slider value at once, before the shortcut, but holds later
values for its 50 ms throttle timer; a browser whose page is starved (headless software GL
at 2-5 frames/s) fires that timer up to ~1 s late, so of a quick burst of presses on a slider
only the first ones are recognised there (measured: 2 of 6 at ~0.15 s apart). Deliberate
presses, and bursts in a browser drawing at normal rates, are.
"""

from __future__ import annotations

import threading
import time
from concurrent.futures import Future
from typing import Callable, Iterable

KEY_WINDOW_S = 0.2
"""How close (seconds) a slider's browser update and an arrow/Home shortcut must be for the shortcut to be
dropped as the slider's own key press; above the client's 50 ms GUI-update throttle with margin."""

SLIDER_KEYS = ("arrowright", "arrowleft", "arrowup", "arrowdown", "home")
"""Keys a focused slider moves with (viser names); their shortcuts go through the guard."""


class SliderKeyGuard:
    """Drops slider-key shortcuts that came with a slider's move; see the module docstring."""

    def __init__(self, window_s: float = KEY_WINDOW_S):
        self.window_s = window_s
        self._lock = threading.Lock()
        self._last_slider_s = -1e9
        """``time.monotonic()`` of the latest slider move made in a browser."""

    def watch(self, handles: Iterable) -> None:
        """Note the browser moves of these slider handles (server-side writes do not count)."""
        for h in handles:
            h.on_update(lambda e: e.client is not None and self.slider_moved())

    def slider_moved(self, at: float | None = None) -> None:
        with self._lock:
            self._last_slider_s = time.monotonic() if at is None else at

    def run(self, action: Callable[[], object], pressed_at: float | None = None) -> Future:
        """Run ``action`` for a shortcut pressed at ``pressed_at`` (monotonic; default now) unless a slider moved
        within ``window_s`` of it. Decided ``window_s`` after the press on a timer thread, not by waiting here: the
        slider's own update callback runs on viser's thread pool too and must not queue behind held shortcuts.
        The future tells whether it ran."""
        pressed = time.monotonic() if pressed_at is None else pressed_at
        done: Future = Future()

        def decide():
            with self._lock:
                moved = abs(self._last_slider_s - pressed) <= self.window_s
            try:
                if not moved:
                    action()
            finally:
                done.set_result(not moved)

        timer = threading.Timer(max(pressed + self.window_s - time.monotonic(), 0.0), decide)
        timer.daemon = True
        timer.start()
        return done


def bind_hotkeys(gui, bindings: Iterable[tuple[str, str, Callable[[], object]]], guard: SliderKeyGuard) -> None:
    """Register ``(label, key, action)`` shortcuts; those on slider keys go through ``guard``."""
    for label, key, fn in bindings:
        cmd = gui.add_command(label, hotkey=key)
        if key in SLIDER_KEYS:
            cmd.on_trigger(lambda e, fn=fn: guard.run(fn))
        else:
            cmd.on_trigger(lambda e, fn=fn: fn())
