"""The wrong-map refusal of the commands that track against a map (``track``, ``refine-map``): one rule, one message.

:mod:`evpose.tracker.map_acquisition` holds the rule and its measurements; this applies it update by update as a
command's session runs, so the command stops within ``acquire_s`` seconds of recording instead of after all of it.
``refine-map`` ran a wrong map through the whole recording and wrote it back unchanged, exit 0 ("0 of 4 measured
points moved"), where ``track`` refused the same pairing.
"""

from __future__ import annotations

from pathlib import Path

from evpose.errors import InputError


class AcquisitionCheck:
    """Feed every update's result to :meth:`update`; it raises :class:`InputError` naming the map once the first
    ``acquire_s`` seconds show that no update registers, or that the registrations are no better than chance."""

    def __init__(self, session, acquire_s: float, map_path: Path, recording_name: str):
        self.session = session
        self.acquire_s = float(acquire_s)
        self.map_path = map_path
        self.recording_name = recording_name
        self.until_us = session.t0_us + int(round(max(self.acquire_s, 0.0) * 1e6))
        self.registered = self.acquire_s <= 0
        # The window's updates also count their inlier share's chance level, which the test reads once.
        self.window: list | None = None if self.acquire_s <= 0 else []
        session.tracker.chance_until_us = None if self.window is None else self.until_us

    def update(self, result) -> None:
        from evpose.tracker.map_acquisition import chance_mismatch, chance_problem, mismatch_problem, registered

        s = self.session
        self.registered = self.registered or registered(result.counts)
        ends = result.t_us >= self.until_us or s.done
        if not self.registered and ends:
            raise InputError(self.map_path, mismatch_problem((result.t_us - s.t0_us) / 1e6, self.recording_name, result.reason),
                             f"updates 1-{len(s.results)}")
        if self.window is not None:
            self.window.append((result.t_us, result.counts))
            if ends:
                z = chance_mismatch(self.window, s.t0_us, self.acquire_s, finished=s.done)
                if z is not None:
                    raise InputError(self.map_path, chance_problem(z, (result.t_us - s.t0_us) / 1e6, self.recording_name),
                                     f"updates 1-{len(s.results)}")
                self.window = None


def check_acquire_s(acquire_s: float) -> None:
    """``--acquire-s`` is a finite number of seconds >= 0 (-1 ran as 0, never give up, silently)."""
    import math

    if not math.isfinite(acquire_s) or acquire_s < 0:
        raise InputError(None, f"--acquire-s must be a finite number of seconds >= 0 (0 = never give up), got {acquire_s}")
