"""app/engine_factory.py: what the viewer opens a recording with."""

import builtins
import sys

import pytest

from app.engine_factory import engine_factory


def test_an_interrupt_while_the_tracker_imports_stops_instead_of_falling_back_to_events_only(monkeypatch, bar_recording):
    # SIGTERM 3 s into `evpose app --prepare` failed gtsam's import ("initialization failed"): the viewer said the
    # tracker was not available in this build and --prepare exited 2 instead of 143.
    real_import = builtins.__import__

    def interrupted_import(name, *args, **kwargs):
        if name == "evpose.tracker.session":
            try:
                raise KeyboardInterrupt
            except KeyboardInterrupt:
                raise ImportError("initialization failed")  # noqa: B904 - as pybind11 does: chained implicitly
        return real_import(name, *args, **kwargs)

    monkeypatch.delitem(sys.modules, "evpose.tracker.session", raising=False)
    monkeypatch.setattr(builtins, "__import__", interrupted_import)
    with pytest.raises(KeyboardInterrupt):
        engine_factory(bar_recording, object())
