"""Player: playback state machine, real-time pacing, stepping, coalescing of parameter changes."""

import dataclasses
import threading
import time

import numpy as np
import pytest

from app.engine import EventsOnlyEngine, EventsViewConfig
from app.frame_cache import quantize
from app.player import Player, PlayerConfig, PlayState, RerunFrom


def _player(rec, **pc):
    frames = []
    lock = threading.Lock()

    def on_frame(frame, engine):
        with lock:
            frames.append(frame)

    p = Player(lambda cfg: EventsOnlyEngine(rec, cfg), on_frame, player_config=PlayerConfig(**pc))
    return p, frames


def test_step_forward_and_back_show_neighbouring_steps(bar_recording):
    p, frames = _player(bar_recording)
    try:
        for _ in range(5):
            p.step_forward()
        p.step_back()
        p.step_back()
        p.wait_idle()
        assert [f.index for f in frames] == [0, 1, 2, 3, 4, 3, 2]
        ref = EventsOnlyEngine(bar_recording)
        for _ in range(3):
            want = ref.step()
        assert np.array_equal(frames[-1].tdf, want.tdf)
    finally:
        p.stop()


def test_play_advances_at_about_real_time_and_pause_stops(bar_recording):
    p, frames = _player(bar_recording, max_ui_fps=60.0)
    try:
        p.play()
        time.sleep(0.4)
        p.pause()
        p.wait_idle()
        t_paused = p.last_frame.t_us
        played_s = (t_paused - bar_recording.t_start_us) / 1e6
        assert 0.1 < played_s < 0.8  # real-time pacing, generous for a busy 2-core machine
        assert p.state == PlayState.PAUSED
        time.sleep(0.2)
        assert p.last_frame.t_us == t_paused
        # After a pause the displayed frame is the engine's current step: stepping back shows the one before.
        p.step_back()
        p.wait_idle()
        assert p.last_frame.index == frames[-2].index - 1 or p.last_frame.t_us < t_paused
    finally:
        p.stop()


def test_play_to_the_end_stops_or_loops(bar_recording):
    p, frames = _player(bar_recording)
    try:
        p.set_speed(10.0)
        p.seek(bar_recording.t_end_us - 50_000)
        p.play()
        p.wait_idle()
        deadline = time.time() + 5
        while p.state == PlayState.PLAYING and time.time() < deadline:
            time.sleep(0.02)
        assert p.state == PlayState.PAUSED
        assert p.last_frame.t_us >= bar_recording.t_end_us
        p.set_loop(True)
        p.seek(bar_recording.t_end_us - 20_000)
        p.play()
        p.wait_idle()
        deadline = time.time() + 5
        while time.time() < deadline and not any(f.index == 0 for f in frames[-5:]):
            time.sleep(0.02)
        p.pause()
        assert any(f.index <= 2 for f in frames[-20:])
    finally:
        p.stop()


def test_the_end_is_drawn_paused_and_each_play_has_its_own_real_time_factor(bar_recording):
    seen = []
    holder = []
    p = Player(lambda cfg: EventsOnlyEngine(bar_recording, cfg), lambda f, e: seen.append(holder[0].stats()))
    holder.append(p)
    try:
        p.set_speed(10.0)
        p.play()
        p.wait_idle()
        deadline = time.time() + 10
        while p.state == PlayState.PLAYING and time.time() < deadline:
            time.sleep(0.02)
        p.wait_idle()
        # The last drawing (what every tab's status line shows) is of the paused player.
        assert seen[-1]["state"] == "paused" and seen[-1]["t_us"] >= bar_recording.t_end_us
        assert seen[-1]["real_time_factor"] > 0
        p.seek(bar_recording.t_start_us)
        p.wait_idle()
        p.play()
        p.pause()
        p.wait_idle()
        assert p.stats()["real_time_factor"] == 0.0  # nothing played since this play began
    finally:
        p.stop()


def test_rapid_parameter_changes_are_coalesced_into_one_rebuild(bar_recording):
    p, frames = _player(bar_recording, coalesce_s=0.3)
    try:
        for _ in range(10):
            p.step_forward()
        p.wait_idle()
        base = EventsViewConfig()
        for k in range(10):
            ts = dataclasses.replace(base.time_surface, eta_ms=5.0 + k)
            p.set_config(dataclasses.replace(base, time_surface=ts))
            time.sleep(0.02)
        assert p.wait_idle()
        assert p.config_applies == 1
        assert p.engine.config.time_surface.eta_ms == 14.0
        # Re-run from the current step: same step, recomputed as a headless run with the new config would.
        assert frames[-1].index == 9
        ref = EventsOnlyEngine(bar_recording, p.engine.config)
        for _ in range(10):
            want = ref.step()
        assert np.array_equal(frames[-1].ts_positive, want.ts_positive)
    finally:
        p.stop()


def test_parameter_change_can_restart_from_the_first_step(bar_recording):
    p, frames = _player(bar_recording, coalesce_s=0.0)
    try:
        for _ in range(6):
            p.step_forward()
        p.set_config(EventsViewConfig(window_us=2_000), RerunFrom.START)
        assert p.wait_idle()
        assert frames[-1].index == 0
        assert frames[-1].t_us == bar_recording.t_start_us + 2_000
    finally:
        p.stop()


def test_commands_from_many_threads_leave_a_consistent_state(bar_recording):
    p, frames = _player(bar_recording)
    try:
        def tab(seed):
            rng = np.random.default_rng(seed)
            for _ in range(30):
                r = rng.integers(3)
                if r == 0:
                    p.step_forward()
                elif r == 1:
                    p.step_back()
                else:
                    p.seek(int(rng.integers(bar_recording.t_start_us, bar_recording.t_end_us)))

        threads = [threading.Thread(target=tab, args=(s,)) for s in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        p.wait_idle()
        last = p.last_frame
        ref = EventsOnlyEngine(bar_recording).seek(last.t_us)
        assert ref.index == last.index and np.array_equal(ref.tdf, last.tdf)
        assert len(p.engine.history) == last.index + 1
    finally:
        p.stop()


def test_tracker_playback_from_the_run_ahead_shows_exact_strided_frames(squares_scene):
    from app.tracker_engine import TrackerEngine
    from evpose.tracker.session import TrackingSession

    rec, cmap = squares_scene
    results = TrackingSession(rec, cmap).run()
    frames = []
    p = Player(lambda cfg: TrackerEngine(rec, cmap, cfg), lambda f, e: frames.append(f),
               player_config=PlayerConfig(max_ui_fps=10.0, draw_share_factor=0.0))
    try:
        p.step_forward()
        p.wait_idle()
        deadline = time.monotonic() + 120
        while p.call(lambda e: e.frontier < e.n_steps).result(60) and time.monotonic() < deadline:
            time.sleep(0.05)
        p.seek(results[40].t_us)
        p.wait_idle()
        assert frames[-1].index == 40  # every step is kept: a seek lands exactly
        n0 = len(frames)
        p.play()
        time.sleep(0.25)
        p.pause()
        p.wait_idle()
        played = frames[n0:]
        assert played and all(b.index - a.index == 20 for a, b in zip(played, played[1:-1]))  # 1x at 10 frames/s, 5 ms steps
        assert all(np.array_equal(f.pose, results[f.index].pose) for f in played)
        p.step_back()
        p.wait_idle()
        assert frames[-1].index == played[-1].index - 1 and np.array_equal(frames[-1].pose, results[frames[-1].index].pose)
    finally:
        p.stop()


class _GatedEngine:
    """Makes a TrackerEngine class whose catch-up slices wait for ``gate`` (the test decides when a slice ends)."""

    @staticmethod
    def make(rec, cmap):
        from app.tracker_engine import TrackerEngine

        gate = threading.Event()
        gate.set()

        class Gated(TrackerEngine):
            def catch_up(self, t_us, budget_steps, exact=False):
                assert gate.wait(30)
                return super().catch_up(t_us, budget_steps, exact)

        return Gated, gate


def _tracker_player(rec, cmap, engine_cls=None, **pc):
    from app.tracker_engine import TrackerEngine

    cls = engine_cls or TrackerEngine
    frames, progress = [], []
    p = Player(lambda cfg: cls(rec, cmap, cfg), lambda f, e: frames.append(f),
               player_config=PlayerConfig(prefetch=False, **pc))
    p._on_progress = lambda e: progress.append(p.stats()["catching_up"])
    return p, frames, progress


def test_a_far_seek_is_computed_in_slices_with_progress_and_shows_the_headless_step(squares_scene):
    from evpose.tracker.session import TrackingSession

    rec, cmap = squares_scene
    results = TrackingSession(rec, cmap).run()
    p, frames, progress = _tracker_player(rec, cmap, catch_up_steps=5, progress_every_s=0.0)
    try:
        p.step_forward()
        p.wait_idle()
        p.seek(results[83].t_us)
        assert p.wait_idle(60)
        # At once a preview of the target (its time surfaces, no pose), then only the seek's frame (the grid step at
        # or before it); the status line heard of each slice.
        assert [(f.index, f.preview) for f in frames] == [(0, False), (80, True), (80, False)]
        assert np.array_equal(frames[-1].pose, results[80].pose) and frames[1].pose is None
        assert np.array_equal(quantize(frames[1].ts_positive), quantize(frames[-1].ts_positive))
        assert np.array_equal(quantize(frames[1].ts_negative), quantize(frames[-1].ts_negative))
        assert p.last_catch_up["preview_s"] is not None
        assert len(progress) >= 10 and all(a <= b for (a, _), (b, _) in zip(progress, progress[1:]))
        assert progress[-1][1] == pytest.approx((results[80].t_us - rec.t_start_us) / 1e6)
        assert p.last_catch_up["outcome"] == "done" and p.last_catch_up["steps"] == 79
        assert p.stats()["catching_up"] is None and p.last_seek_ms > 0
        hist = p.call(lambda e: e.history).result(10)
        assert all(np.array_equal(h.pose, r.pose) for h, r in zip(hist, results)) and len(hist) == 81
    finally:
        p.stop()


def test_a_new_seek_replaces_a_catch_up_and_pause_cancels_one(squares_scene):
    from evpose.tracker.session import TrackingSession

    rec, cmap = squares_scene
    results = TrackingSession(rec, cmap).run()
    cls, gate = _GatedEngine.make(rec, cmap)
    p, frames, _ = _tracker_player(rec, cmap, cls, catch_up_steps=5)
    try:
        p.step_forward()
        p.wait_idle()
        gate.clear()
        p.seek(results[60].t_us)
        p.seek(results[90].t_us)  # heard after the slice the worker waits in (or before it starts)
        gate.set()
        assert p.wait_idle(60)
        # Only the second target is shown (the grid step at or before it: every 4th step is kept), after previews.
        assert [f.index for f in frames if not f.preview] == [0, 88] and np.array_equal(frames[-1].pose, results[88].pose)
        assert [f.index for f in frames if f.preview][-1] == 88
        # A seek back inside what was computed answers at once; a far one cancelled by pause shows nothing new.
        p.seek(results[40].t_us)
        p.wait_idle(60)
        assert frames[-1].index == 40 and np.array_equal(frames[-1].pose, results[40].pose)
    finally:
        p.stop()
    p, frames, _ = _tracker_player(rec, cmap, cls, catch_up_steps=5)
    try:
        p.step_forward()
        p.wait_idle()
        gate.clear()
        p.seek(results[90].t_us)
        p.pause()
        gate.set()
        assert p.wait_idle(60)
        # The preview of 90 was drawn; pause puts every tab back on the step the engine is at.
        assert [(f.index, f.preview) for f in frames][:2] == [(0, False), (88, True)]
        assert p.last_catch_up["outcome"] == "cancelled" and frames[-1].index == 0 and not frames[-1].preview
        assert p.call(lambda e: e.frontier).result(10) < 90
    finally:
        p.stop()


def test_an_engine_the_player_lets_go_is_released(bar_recording):
    released = []

    class Recorded(EventsOnlyEngine):
        def release(self):
            released.append(self)

    made = []
    factory = lambda cfg: made.append(Recorded(bar_recording, cfg)) or made[-1]  # noqa: E731
    p = Player(factory, lambda f, e: None, player_config=PlayerConfig(coalesce_s=0.0))
    try:
        p.step_forward()
        p.set_config(EventsViewConfig(window_us=10_000))  # a new configuration: a new engine
        p.wait_idle()
        p.load(factory)  # another recording
        p.wait_idle()
        assert released == made[:2] and p.engine is made[2]
    finally:
        p.stop()


def test_play_on_a_last_step_before_the_last_event_starts_again_from_the_first(bar_recording):
    # The tracker's last step lies up to a step before the last event: play there paused at once and did nothing.
    class EndsEarly(EventsOnlyEngine):
        @property
        def n_steps(self) -> int:
            return super().n_steps - 1

    frames = []
    p = Player(lambda cfg: EndsEarly(bar_recording, cfg), lambda f, e: frames.append(f))
    try:
        p.seek(bar_recording.t_end_us)
        p.wait_idle()
        last = frames[-1]
        assert last.t_us < bar_recording.t_end_us and last.index == p.engine.n_steps - 1
        p.play()
        p.wait_idle()
        p.pause()
        p.wait_idle()
        assert any(f.index == 0 for f in frames[frames.index(last) + 1:])
    finally:
        p.stop()


def test_a_step_that_fails_while_playing_redraws_the_step_shown_paused_before_the_error(bar_recording, monkeypatch):
    # The tab's status line was left at "playing" (and a failed far seek at its preview's "computing ...").
    said = []
    p, frames = _player(bar_recording, max_ui_fps=60.0)
    p._on_error = lambda message: said.append((message, p.state, len(frames)))
    try:
        p.step_forward()
        p.wait_idle()

        def failing(self, stride=1):
            raise RuntimeError("boom")

        monkeypatch.setattr(EventsOnlyEngine, "play_step", failing)
        p.play()
        deadline = time.time() + 10
        while not said and time.time() < deadline:
            time.sleep(0.02)
        p.wait_idle()
        assert said == [("step failed: boom", PlayState.PAUSED, 2)]  # a redraw (frame 2) came before the message
        assert frames[-1].index == 0 and p.state == PlayState.PAUSED
    finally:
        p.stop()


def test_play_goes_over_a_stretch_without_events_at_once_and_says_so(bar_recording):
    # A 60 s gap held the display still for a minute at "playing at 1.0x" (the tracker's steps skip a long gap, so
    # its next frame was due 60 s later; the events-only view and SLAM step through it with empty steps).
    from evpose.core.events import EventArray

    ev = bar_recording.events
    t = ev.t.copy()
    t[t >= 300_000] += 3_000_000  # no events from 0.3 to 3.3 s
    rec = dataclasses.replace(bar_recording, events=EventArray(t, ev.x, ev.y, ev.p))
    p, frames = _player(rec, max_ui_fps=60.0, prefetch=False)
    try:
        p.seek(rec.t_start_us + 250_000)
        p.wait_idle()
        p.play()
        t0 = time.time()
        while p.last_frame.t_us < rec.t_start_us + 3_350_000 and time.time() - t0 < 2.5:
            time.sleep(0.02)
        p.pause()
        p.wait_idle()
        assert p.last_frame.t_us >= rec.t_start_us + 3_350_000, "the gap was waited for in real time"
        lo, hi = p.stats()["skipped_gap"]
        assert lo <= rec.t_start_us + 300_000 + 500_000 and hi >= rec.t_start_us + 3_000_000
        assert p.stats()["real_time_factor"] < 3.0  # the gap is not counted in it
        p.step_back()
        p.wait_idle()
        assert p.stats()["skipped_gap"] is None  # said until the next command
        # The tracker's steps skip a long gap: the next frame is the step after it, tens of seconds on.
        shown = dataclasses.replace(frames[-1], index=10, t_us=1_000_000, counts={"events_in": 50})
        after = dataclasses.replace(shown, index=11, t_us=61_000_000)
        assert p.quiet.ending_at(after, shown, 5_000, 500_000) == (1_000_000, 61_000_000)
        assert p.quiet.ending_at(dataclasses.replace(after, t_us=1_005_000), shown, 5_000, 500_000) is None
    finally:
        p.stop()


def test_an_exact_seek_shows_that_very_step_not_the_kept_frame_before_it(squares_scene):
    # A lesson bookmark goes back to the step saved (app/bookmark_gui.py); the slider's seek may land on the grid.
    rec, cmap = squares_scene
    p, frames, _ = _tracker_player(rec, cmap)
    try:
        p.step_forward()
        p.wait_idle()
        t83 = p.call(lambda e: e.seek_step(83).t_us).result(60)
        p.seek(t83)
        assert p.wait_idle(60) and frames[-1].index == 80  # snapped to the frame grid (every 4 steps of 5 ms)
        p.seek(t83, exact=True)
        assert p.wait_idle(60) and frames[-1].index == 83 and frames[-1].t_us == t83
    finally:
        p.stop()


def test_a_pause_arriving_just_after_playback_ended_does_not_play_it_again_from_the_start(bar_recording):
    # A busy page delivered the pause 4.7 s late, after the end: as a press at the last step it replayed everything.
    p, frames = _player(bar_recording, late_pause_s=0.5)
    try:
        p.set_speed(10.0)
        p.seek(bar_recording.t_end_us - 50_000)
        p.play()
        deadline = time.time() + 5
        while (p.state == PlayState.PLAYING or p._ended_at is None) and time.time() < deadline:
            time.sleep(0.01)
        ended = len(frames)
        p.toggle()  # the late pause
        p.wait_idle()
        assert p.state == PlayState.PAUSED and all(f.index > 2 for f in frames[ended:])
        time.sleep(0.6)
        p.toggle()  # a press after late_pause_s: play again from the start, as before
        p.wait_idle()
        deadline = time.time() + 5
        while not any(f.index <= 2 for f in frames[ended:]) and time.time() < deadline:
            time.sleep(0.02)
        assert any(f.index <= 2 for f in frames[ended:])
    finally:
        p.stop()
