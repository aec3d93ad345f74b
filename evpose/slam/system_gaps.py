"""Where the SLAM system's input pauses: a long stretch without events, or in event-inertial mode without IMU samples,
ends the active map (:class:`evpose.slam.system.EventSlam` inherits it).

Across such a pause the camera may have moved anywhere, so nothing that links consecutive MCIs (KLT tracks, the
motion prior, an IMU bridge, a two-view reference) stays valid. The pause is one ``LOST`` step result with failure
``gap``, at the first event after it: the step statistics credit the pause to it, not to tracking. In event-inertial
mode the events inside an IMU hole longer than ``TrackingConfig.lose_after_gap_s`` are dropped (nothing could
propagate or constrain a pose there), which turns the hole into a pause of the events; so are the events more than
that after the IMU's last sample (or before its first).

The methods read the system's ``cfg``, ``imu``, ``calib``, ``atlas``, ``fe``, ``results`` and ``_state`` and call
its ``_lose``.

The end of the stream is the last pause: :meth:`StreamGaps.finish` turns the events collected after the last
reconstruction window into one more MCI (``EventWindowConfig.flush_min_fraction``), so a recording's tail is tracked
like the rest of it.
"""

from __future__ import annotations

import numpy as np

from evpose.core.events import EventArray
from evpose.core.stream_gaps import EventGap, find_gaps
from evpose.slam.features import FrontendTracks
from evpose.slam.step_result import SlamFailure, SlamStatus, SlamStepResult

_NEVER = np.iinfo(np.int64).max


def imu_holes(imu, time_offset_us: int, longer_than_us: int) -> list[EventGap]:
    """Stretches of the camera clock without IMU samples longer than ``longer_than_us``, and those more than that
    before the first and after the last sample (open-ended: the int64 extremes), in time order."""
    t = np.asarray(imu.t, np.int64) - int(time_offset_us)
    holes = [EventGap(-_NEVER, int(t[0]) - longer_than_us, "IMU samples")]
    holes += find_gaps(t, longer_than_us, -_NEVER, "IMU samples")
    holes.append(EventGap(int(t[-1]) + longer_than_us, _NEVER, "IMU samples"))
    return holes


class StreamGaps:
    """Ending maps at pauses of the input for :class:`evpose.slam.system.EventSlam` (a mixin: its state lives in the
    system: ``_gap_last_t``, the newest event kept, ``_imu_holes`` and ``_imu_end_reported``)."""

    def _gap_limit_us(self) -> int:
        return int(round(self.cfg.tracking.lose_after_gap_s * 1e6))

    def _segments(self, events: EventArray) -> list[tuple[EventArray, EventGap | None]]:
        """``events`` split at the pauses: ``(events after the pause, the pause or None)`` in time order; the events
        inside IMU holes are left out (event-inertial mode)."""
        lim = self._gap_limit_us()
        if lim <= 0 or not len(events):
            return [(events, None)]
        t = events.t
        ended: list = []
        if self._imu_holes:
            keep = np.ones(len(t), bool)
            for h in self._imu_holes:
                if h.t_last_us < int(t[-1]) and h.t_next_us > int(t[0]):
                    inside = (t > h.t_last_us) & (t < h.t_next_us)
                    keep &= ~inside
                    if h.t_next_us == _NEVER and not self._imu_end_reported:
                        # The IMU stops before the events: said once, at the first event it leaves without samples.
                        self._imu_end_reported = True
                        t_first = int(t[np.argmax(inside)])
                        ended = [(events[:0], EventGap(h.t_last_us, t_first, "IMU samples"))]
            if not keep.all():
                events, t = events[keep], t[keep]
                if not len(t):
                    return ended
        prev = self._gap_last_t if self._gap_last_t is not None else int(t[0])
        d = np.diff(t, prepend=prev)
        cuts = np.flatnonzero(d > lim)
        self._gap_last_t = int(t[-1])
        if not len(cuts):
            return [(events, None)] + ended
        out = [(events[: int(cuts[0])], None)] if cuts[0] > 0 else []
        bounds = list(cuts) + [len(t)]
        for a, b in zip(bounds[:-1], bounds[1:]):
            a, b = int(a), int(b)
            t_last = int(t[a - 1]) if a > 0 else prev
            out.append((events[a:b], EventGap(t_last, int(t[a]), self._gap_stream(t_last, int(t[a])))))
        return out + ended

    def _gap_stream(self, t_last: int, t_next: int) -> str:
        imu = any(h.t_last_us < t_next and h.t_next_us > t_last for h in self._imu_holes)
        return "IMU samples" if imu else "events"

    def _end_at_gap(self, gap: EventGap) -> SlamStepResult:
        """Close the active map (or the initialisation in progress) at ``gap``; the step result that stands for it."""
        if self._imu_end_reported and gap.stream == "IMU samples" and gap.t_last_us == self._imu_holes[-1].t_last_us:
            reason = f"the IMU samples end at t={(gap.t_last_us - self._gap_limit_us()) * 1e-6:.6f} s, before the events"
            after = "the events after it are not used"
        else:
            reason = f"no {gap.stream} for {gap.seconds:.3f} s (t={gap.t_last_us * 1e-6:.6f} to {gap.t_next_us * 1e-6:.6f} s)"
            after = "a new map starts after it"
        m = self.atlas.active
        if m is not None and m.keyframes:
            self._lose(reason)
        else:
            self._state = SlamStatus.NOT_INITIALISED
        self.fe = FrontendTracks(next_id=self.fe.next_id)
        self._rejoin = None
        result = SlamStepResult(gap.t_next_us, SlamStatus.LOST, f"input paused: {reason}; {after}",
                                failure=SlamFailure.GAP, map_id=m.id if m else -1)
        self.results.append(result)
        return result

    def finish(self) -> SlamStepResult | None:
        """End of the stream: the events the window selection holds after its last reconstruction window become one
        more, forced window when there are enough of them (``EventWindowConfig.flush_min_fraction``) and are processed
        as any other; its result (also appended to ``results``), else None. Call once, after the last :meth:`step`."""
        rw = self.window.flush()
        if rw is None:
            return None
        result = self._process_window(rw)
        result.mcis = 1
        result.tiny_frame = self.window.last_tiny_image
        self.results.append(result)
        return result
