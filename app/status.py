"""The playback status line: the shown step, the player's state and achieved speed, and how far the run-ahead is."""

from __future__ import annotations

from app.engine import Engine
from app.engine_factory import NO_MAP_NOTE
from app.frame import Frame
from evpose.core.stream_gaps import EventGap, find_gaps
from evpose.tracker.map_acquisition import chance_mismatch, map_mismatch


def run_ahead_note(engine: Engine) -> str:
    """'run-ahead: 4.20 of 10.00 s ready' for engines with a run-ahead (empty otherwise); says what came from disk."""
    n = getattr(engine, "n_steps", None)
    frontier = getattr(engine, "frontier", None)
    step_us = getattr(engine, "step_us", None)
    if not n or frontier is None or not step_us:
        return ""
    ready = getattr(engine, "ready_steps", frontier)
    # Seconds of recording the first k steps cover (past a long event gap no longer k * step_us: the tracker's engine).
    secs = getattr(engine, "seconds_of_steps", None) or (lambda k: k * step_us / 1e6)
    total = secs(n)
    disk = getattr(engine, "disk", None)
    note = ""
    if disk is not None and getattr(engine, "disk_steps", 0) > frontier:
        note = f" ({secs(engine.disk_steps):.2f} s read from the disk cache; exact single steps there need the run-ahead, at {secs(frontier):.2f} s)"
    if disk is not None and disk.error:
        note += f" ({disk.error})"
    left = getattr(engine, "backfill_left", 0)
    if left and ready >= n:
        return (f"run-ahead: all {total:.2f} s computed; filling in {left} frames a far seek skipped "
                "(seeks there replay from a snapshot meanwhile)" + note)
    if left:
        note += f" ({left} frames a far seek skipped are filled in afterwards)"
    if ready >= n:
        return f"run-ahead done: all {total:.2f} s ready (seeks and 1x playback from memory)" + note
    return f"run-ahead: {secs(ready):.2f} of {total:.2f} s ready (computing; beyond it, steps are computed live)" + note


def map_mismatch_note(engine: Engine) -> str:
    """A warning when no update has registered against the map since the start for as long as ``evpose track``
    allows, or when the registrations of that first second are no better than chance (both rules of
    :mod:`evpose.tracker.map_acquisition`), or, once every step is computed, in the whole of a recording shorter than
    that (``evpose track`` and ``app --prepare`` report it at the end); empty for engines without a map, or for a map
    that passes."""
    history = getattr(engine, "history", None)
    if getattr(engine, "contour_map", None) is None or not history:
        return ""
    session = getattr(engine, "session", None)  # tracking starts at the first ground-truth pose, as in the CLI
    t0_us = getattr(session, "t0_us", engine.t_start_us)
    steps = [(h.t_us, h.counts) for h in history]
    s = map_mismatch(steps, t0_us)
    if s is not None:
        return (f"**no update has registered against this map in the first {s:.2f} s**: is it this recording's map, in "
                "its frame? The poses shown are the motion model's (`evpose track` stops here with an error).")
    z = chance_mismatch(steps, t0_us)
    if z is not None:
        return (f"**this map's points lie on recent events hardly more often than chance in the first second** (z {z:.1f}):"
                " is it this recording's map, in its frame? (`evpose track` stops here with an error.)")
    known = getattr(engine, "known_summaries", None)
    n = getattr(engine, "n_steps", None)
    # Whatever step is shown: the run-ahead has seen every step, and the recording ended before acquire-s.
    if not known or not n or len(known) < n:
        return ""
    s = map_mismatch(((h.t_us, h.counts) for h in known), t0_us, finished=True)
    if s is None:
        return ""
    return (f"**no update registered against this map in the whole recording ({s:.2f} s)**: is it this recording's "
            "map, in its frame? The poses shown are the motion model's (`evpose track` ends with an error).")


GAP_NOTE_S = 1.0
"""A stretch of a recording without events at least this long is named in the status line at the steps in it or
just before it, seconds."""
GAP_BEFORE_S = 0.1
"""How close before a gap a step is said to be at it, seconds: a seek into a long gap lands on the tracker's last
step before it (its steps skip the gap), up to a cache grid's few steps earlier."""


def event_gaps(events_t) -> list[EventGap]:
    """The recording's stretches without events of at least :data:`GAP_NOTE_S`."""
    return find_gaps(events_t, int(GAP_NOTE_S * 1e6) - 1, -(2 ** 62))


def gap_note(frame: Frame, gaps: list[EventGap], steps_skip_gaps: bool = False, t0_us: int = 0) -> str:
    """Which gap the step shown lies in or just before, in words (empty if none). A seek to 30 s in a recording
    without events from 2 to 62 s showed the tracker's step at 1.995 s, the time slider jumped back there, and nothing
    said why; SLAM's steps in the gap read "waiting — tracking features in tiny frames" (``steps_skip_gaps``: the
    engine's steps skip a long gap, the tracker's; ``t0_us``: the recording's start, times are said from it)."""
    for g in gaps:
        if g.t_last_us - GAP_BEFORE_S * 1e6 <= frame.t_us < g.t_next_us:
            head = f"_no events from {(g.t_last_us - t0_us) / 1e6:.3f} to {(g.t_next_us - t0_us) / 1e6:.3f} s ({g.seconds:.1f} s)"
            if steps_skip_gaps:
                return f"{head}: the tracker's steps skip it (a seek into it shows the last step before it); play goes over it at once_"
            where = "this step lies in it" if frame.t_us > g.t_last_us else "after this step"
            # SLAM steps through a gap: play does not wait for it, but computes its empty steps (0.3x measured).
            return f"{head}: {where}; play does not wait for it in real time, it computes its empty steps_"
    return ""


def status_markdown(frame: Frame, engine: Engine, stats: dict, gaps: list[EventGap] = ()) -> str:
    """Markdown of the status line under the playback controls (``gaps``: the recording's, :func:`event_gaps`)."""
    # From the recording's start, as the time slider: a recording on a clock of its own (100 s at its first event)
    # read "t = 101.495 s" beside a slider at 1.495.
    t0 = getattr(engine, "t_start_us", 0)
    text = (f"t = {(frame.t_us - t0) / 1e6:.3f} s, step {frame.index}, **{frame.status}**"
            # A dash, not parentheses: the reasons carry their own ("40 inliers (2 re-found by projection)").
            # Events only for want of a map: said under the recording list. Any other reason (no calibration, a
            # rejected configuration) is said here, where the eye goes when nothing is tracked.
            # The tracker's reasons are the command line's too: "--mode stpe" is the Parameters' *mode* here.
            + (f" — {frame.reason.replace('--mode stpe', 'mode stpe')}" if frame.reason and frame.reason != NO_MAP_NOTE else "")
            + f"\n\n{stats.get('state', '')} at {stats.get('speed', 1):.1f}x")
    if stats.get("real_time_factor", 0) > 0:  # 0 until something is played: "real-time factor 0.00" read as a stall
        text += f", real-time factor {stats['real_time_factor']:.2f}"
    if stats.get("state") == "paused" and engine.is_last(frame):
        # Forward did nothing here without a word.
        text += "\n\n_the end of the recording: play starts it again from the beginning_"
    elif stats.get("state") == "paused" and frame.index == 0:
        # "< back" did nothing here without a word too (session 27 audit).
        text += "\n\n_the first step of the recording: nothing before it_"
    note = gap_note(frame, gaps, hasattr(engine, "seconds_of_steps"), t0)
    if note:
        text += f"\n\n{note}"
    gap = stats.get("skipped_gap")
    if gap is not None and not note:  # after the gap: what playback did
        text += (f"\n\n_no events from {(gap[0] - t0) / 1e6:.2f} to {(gap[1] - t0) / 1e6:.2f} s "
                 f"({(gap[1] - gap[0]) / 1e6:.1f} s): not waited for in real time_")
    catching = stats.get("catching_up")
    if catching is not None:
        shown = ("the images are already the target's time surfaces; its pose and map overlay follow" if frame.preview
                 else "no images on the way")
        # "Tracking is causal" was said in SLAM mode too, which tracks no map.
        what = "SLAM" if frame.slam is not None else "tracking"
        text += (f"\n\n**computing {catching[0]:.1f} / {catching[1]:.1f} s** to reach the seek ({what} is causal: "
                 f"every step before it is needed; {shown}). Seek elsewhere or pause to cancel.")
    mismatch = map_mismatch_note(engine)
    if mismatch:
        text += f"\n\n{mismatch}"
    note = run_ahead_note(engine)
    return text + (f"\n\n{note}" if note else "")
