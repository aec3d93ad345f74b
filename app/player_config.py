"""The player's choices and settings: play state, where a configuration change re-runs from, pacing and coalescing."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field


class PlayState(str, enum.Enum):
    """Whether the worker advances the engine on its own."""

    PAUSED = "paused"
    PLAYING = "playing"


class RerunFrom(str, enum.Enum):
    """Where a configuration change restarts the computation."""

    CURRENT = "current step"
    """Recompute up to the current time with the new configuration (what a headless run with it shows there)."""
    START = "start"
    """Go back to the first step."""


@dataclass
class PlayerConfig:
    """Pacing and coalescing of the player."""

    max_ui_fps: float = field(default=20.0, metadata={"min": 1.0, "max": 60.0, "step": 1.0, "unit": "Hz"})
    """Most frames a second pushed to the browser while playing, Hz."""
    coalesce_s: float = field(default=0.3, metadata={"min": 0.0, "max": 2.0, "step": 0.05, "unit": "s"})
    """Quiet time after the last parameter change before the engine is rebuilt, seconds."""
    max_lag_s: float = field(default=0.5, metadata={"min": 0.1, "max": 5.0, "step": 0.1, "unit": "s"})
    """Lag behind the wall clock after which pacing restarts from now instead of rushing, seconds."""
    draw_share_factor: float = field(default=3.0, metadata={"min": 0.0, "max": 20.0, "step": 0.5, "unit": "ratio"})
    """While playing, frames are at least this many draw durations apart, so drawing cannot starve the engine, ratio."""
    prefetch: bool = True
    """Run ahead in idle time (in slices): the engine computes later steps and keeps their frames, so playback
    and seeks inside that reach are read back instead of computed."""
    prefetch_steps: int = field(default=5, metadata={"min": 1, "max": 500, "step": 1, "unit": "steps"})
    """Steps per prefetch slice (a command waits at most one slice), steps."""
    prefetch_while_playing: bool = True
    """While playing, spend the wait for the next frame's display time running ahead too (one step at a time)."""
    snap_seeks: bool = True
    """Seeks may land up to one frame-cache interval (``FrameCacheConfig.every_ms``) before the asked time when that frame is ready."""
    catch_up_steps: int = field(default=25, metadata={"min": 1, "max": 1000, "step": 1, "unit": "steps"})
    """A seek whose target needs more steps computed than this is made in slices of this many (a catch-up):
    commands are heard in between (a new seek replaces the target, pause or a step cancels it) and the status
    line shows the progress, steps."""
    preview_seeks: bool = True
    """While a far seek is computed, show at once what needs no pose: the target step's time surfaces and events
    (``Engine.preview``)."""
    progress_every_s: float = field(default=0.5, metadata={"min": 0.1, "max": 5.0, "step": 0.1, "unit": "s"})
    """Time between two status-line updates while the engine works with nothing new shown, seconds."""
    late_pause_s: float = field(default=2.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "s"})
    """A play / pause press (the button, Space) that arrives this soon after playback stopped by itself at the end is
    taken as the pause it was, pressed while the page still showed it playing, seconds; 0 = off. On a busy page
    (software WebGL drawing every frame, 2 shared cores) a click reached the server 1.9 s and 4.7 s after it was made
    (session 31, /tmp/s31/fuzz31/gui/fuzz.py phase ``trace``): a pause pressed 1.3 s before the end of the 4 s demo
    arrived after it and, as a press at the last step does, played the whole recording again from the start. A play
    wanted at the end within this time takes a second press."""
    skip_gaps_s: float = field(default=0.5, metadata={"min": 0.05, "max": 60.0, "step": 0.05, "unit": "s"})
    """While playing, a stretch of the recording without events longer than this is gone over at once instead of in
    real time, seconds (the status line says so). A 60 s gap held the display still for a minute at "playing at
    1.0x": the tracker's steps skip a long gap (one update stands for it), so the next frame was due 60 s later;
    SLAM steps through it with empty steps. Measured as the media time between two frames beyond what their steps
    cover, or as frames without events in a row (a frame counts its own step's events only, so a sparse recording's
    frames read 0 now and then: hence a run this long, not one empty frame)."""
