"""Stretches of a recording without events, which playback goes over at once instead of in real time.

A 60 s gap held the display still for a minute at "playing at 1.0x": the tracker's steps skip a long event gap (one
update stands for it), so the frame after it was due 60 s later; the events-only view and SLAM step through it with
empty steps. :class:`QuietStretches` tells the player (app/player.py) when the frame to show ends such a stretch
longer than ``PlayerConfig.skip_gaps_s``: then it is shown at once and the pacing starts again from it.
"""

from __future__ import annotations

from app.frame import Frame


class QuietStretches:
    """Follows the frames played for stretches without events; see the module docstring."""

    def __init__(self):
        self.since_us: int | None = None
        """Time of the last frame played that had events, while the frames after it have none (else None)."""
        self.skipped: tuple[int, int] | None = None
        """(from, to) us of the stretch playback last went over at once (said in the status line until a command)."""

    def reset(self) -> None:
        """A command (seek, step, play, a new recording): what was skipped is no longer what is shown."""
        self.since_us = self.skipped = None

    def ending_at(self, frame: Frame, prev: Frame | None, step_us: int | None, longer_us: float) -> tuple[int, int] | None:
        """(from, to) us of a stretch without events longer than ``longer_us`` that ends at ``frame`` (None if none):
        media time between the frame shown (``prev``) and it beyond what its steps cover (the tracker skips a long
        gap), or a run of frames without events (SLAM steps through it). A frame counts its own step's events only,
        so a sparse recording's frames read 0 now and then: hence a run this long, not one empty frame."""
        if prev is None or frame.preview:
            return None
        if frame.t_us - prev.t_us - max(frame.index - prev.index, 0) * (step_us or 0) > longer_us:
            self.since_us = None
            return prev.t_us, frame.t_us
        if frame.counts.get("events_in", 1) > 0:
            self.since_us = None
            return None
        if self.since_us is None:
            self.since_us = prev.t_us
        return (self.since_us, frame.t_us) if frame.t_us - self.since_us > longer_us else None

    def went_over(self, gap: tuple[int, int]) -> None:
        """Playback went over ``gap`` at once; one after another (SLAM's empty frames) make one stretch."""
        joined = self.skipped is not None and self.skipped[1] >= gap[0]
        self.skipped = (min(gap[0], self.skipped[0]) if joined else gap[0], gap[1])

    def quiet_for_us(self, t_us: int) -> int:
        """How long before ``t_us`` the frames have had no events (0 when the last one had some)."""
        return 0 if self.since_us is None else t_us - self.since_us
