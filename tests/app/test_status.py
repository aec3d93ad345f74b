"""Status line: says how far the run-ahead is, and nothing about it for engines without one."""

from types import SimpleNamespace

import numpy as np

from app.engine import EventsOnlyEngine
from app.frame import Frame
from app.status import run_ahead_note, status_markdown
from evpose.core.events import EventArray


def test_run_ahead_note_reports_progress_and_completion():
    eng = SimpleNamespace(n_steps=2000, frontier=840, step_us=5000)
    assert run_ahead_note(eng).startswith("run-ahead: 4.20 of 10.00 s ready")
    eng.frontier = 2000
    assert "done" in run_ahead_note(eng)


def test_events_only_status_has_no_run_ahead_note(bar_recording):
    eng = EventsOnlyEngine(bar_recording)
    z = np.zeros((2, 2), np.float32)
    f = Frame(3, 15_000, z, z, z, EventArray.empty(), EventArray.empty())
    text = status_markdown(f, eng, {"state": "paused", "speed": 1.0, "real_time_factor": 0.5})
    assert "step 3" in text and "real-time factor 0.50" in text and "run-ahead" not in text
