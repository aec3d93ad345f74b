"""The viewer's SLAM engine ends the recording as run_slam does: the events after the last reconstruction window
make one more MCI at the last step (``EventWindowConfig.flush_min_fraction``)."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "slam"))
from slam_synthetic import make_recording  # noqa: E402

from app.slam_engine import SlamEngine  # noqa: E402
from tests.app.test_slam_engine import all_steps  # noqa: E402
from evpose.slam import SlamConfig, run_slam  # noqa: E402


def test_last_step_flushes_the_tail_like_a_headless_run():
    rec = make_recording(duration_s=0.6, speed=2.0, seed=3)
    eng = SlamEngine(rec)
    frames = all_steps(eng)
    headless = run_slam(rec, SlamConfig(), chunk_us=eng.config.step_us)
    assert sum(f.counts["mcis"] for f in frames) == len(headless.results)
    # The last step made the flushed MCI: its pose is the headless run's last one, later than any step's before it.
    last, end = frames[-1], headless.results[-1]
    assert last.counts["mcis"] >= 1 and last.status == end.status.value == "ok"
    assert np.array_equal(last.pose, end.pose)
    assert end.t_us > max(r.t_us for r in headless.results[:-1])
