"""A far seek being computed in slices by the player (see ``Player._seek``): its target, progress and cost.

Tracking is causal, so the state at ``t`` needs every step before ``t``. When a
seek lands past what the engine has computed, the player asks the engine for
those steps a slice at a time (``Engine.catch_up``), hearing commands in
between, and shows the seek's frame once they are done.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field


@dataclass
class CatchUp:
    """A seek whose target is being computed in slices."""

    t_us: int
    """Asked time, microseconds."""
    exact: bool
    """Exactly that step (else the kept-frame grid step at or before it)."""
    steps: int
    """Steps that were left to compute when it started."""
    progress: tuple[float, float] = (0.0, 0.0)
    """(media seconds reached, media seconds of the target) from the recording's start, seconds."""
    cpu_s: float = 0.0
    """Thread CPU spent on it so far, seconds."""
    wall0: float = field(default_factory=time.perf_counter)
    """When it was asked for (``time.perf_counter``), seconds."""
    preview_s: float | None = None
    """Seconds from the ask until the preview (``Engine.preview``) was drawn; None without one."""

    def report(self, outcome: str) -> dict:
        return {"t_us": self.t_us, "steps": self.steps, "wall_s": time.perf_counter() - self.wall0,
                "cpu_s": self.cpu_s, "preview_s": self.preview_s, "outcome": outcome}
