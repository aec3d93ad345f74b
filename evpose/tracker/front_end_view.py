"""The front end's images at any update of a session, rebuilt from a bounded stretch of events, without the pose.

The noise filter and the SP-TS never read the pose (unless the ego-motion filter
is on), so their state at update ``k`` is a function of the events alone - and of
only the most recent ones:

* the noise filter keeps an event when a neighbour fired within ``window_us``
  before it, and every event stamps its pixel, so the decision for an event at
  ``t`` depends only on the events in ``[t - window_us, t)``;
* an SP-TS pixel reads ``exp(-(t - t_last) / eta)`` in float32, which is exactly
  0 once ``(t - t_last) / eta`` exceeds ``ln 2^150 = 103.97`` (below half the
  smallest subnormal).

So replaying the events of the last ``104.5 eta + window_us`` before update ``k``
through a fresh filter and surface gives the tracker's own SP-TS images at ``k``
bit for bit, in a few milliseconds, however far ``k`` is from anything computed.
The viewer shows them at once when a seek lands where the pose (which is causal:
it needs every update before it) is still being computed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evpose.core.events import EventArray
from evpose.frontend.distance_field import TemporalDistanceField
from evpose.frontend.noise_filter import ConsistencyNoiseFilter
from evpose.frontend.time_surface import SeparatedTimeSurface

UNDERFLOW_ETAS = 104.5
"""Ages, in units of ``eta``, past which the float32 SP-TS value is exactly 0 (``ln 2^150 = 103.97``, with margin)."""


@dataclass
class FrontEndView:
    """The front end at one update, as the tracker's debug products show it."""

    step_index: int
    """Update number (0-based, as in ``TrackingSession.results``)."""
    t_us: int
    """Time of the update, microseconds."""
    ts_positive: np.ndarray
    """SP-TS of ON events at ``t_us``, float32 (H, W); equal to the tracker's (see :attr:`exact`)."""
    ts_negative: np.ndarray
    """SP-TS of OFF events, float32 (H, W)."""
    tdf: np.ndarray
    """Combined-polarity distance field over the whole image, float32 (H, W) (the tracker computes it only in a box
    around the projected map, which needs the pose)."""
    events_kept: EventArray
    """The update's events that passed the noise filter."""
    events_removed: EventArray
    """The update's events the noise filter removed."""
    exact: bool
    """The images and event split equal the tracker's (False when the ego-motion filter, which reads the pose,
    also removes events)."""


def replay_span_us(config) -> int:
    """Events this long before an update fix the front end's state at it, microseconds (``config``: TrackerConfig)."""
    eta_us = float(config.time_surface.eta_ms) * 1e3
    return int(math.ceil(UNDERFLOW_ETAS * eta_us)) + int(config.noise_filter.window_us) + 1


def front_end_at(session, step_index: int) -> FrontEndView:
    """The SP-TS images, full-image TDF and noise-filter split of update ``step_index`` of ``session``
    (a :class:`~evpose.tracker.session.TrackingSession`; its own state is not touched)."""
    cfg = session.config
    k = int(np.clip(step_index, 0, max(session.total_steps - 1, 0)))
    until = session.t0_us + (k + 1) * session.dt_us
    ev = session.recording.events
    cal = session.recording.calibration
    # The session's front end has seen events from its warm-up start on (``TrackingSession.__init__``).
    warm_start = session.t0_us - int(round(cfg.warmup_ms * 1e3))
    i_first = int(np.searchsorted(ev.t, max(warm_start, until - replay_span_us(cfg)), side="left"))
    # Update k consumes [t_(k-1), t_k) (update 0: from the warm-up's end, t0).
    i_step = max(int(np.searchsorted(ev.t, until - session.dt_us, side="left")), i_first)
    i_end = int(np.searchsorted(ev.t, until, side="left"))
    noise = ConsistencyNoiseFilter(cfg.noise_filter, cal.width, cal.height)
    surface = SeparatedTimeSurface(cfg.time_surface, cal.width, cal.height, cal)
    span = ev[i_first:i_end]
    keep = noise.filter(span)
    surface.update(span, keep)
    field = TemporalDistanceField(cfg.distance_field, cal.width, cal.height)
    field.compute(surface, until, polarities=(0,))
    step_events, step_keep = ev[i_step:i_end], keep[i_step - i_first:]
    return FrontEndView(
        step_index=k, t_us=int(until), ts_positive=surface.image(until, 1), ts_negative=surface.image(until, -1),
        tdf=field.image(0), events_kept=step_events[step_keep], events_removed=step_events[~step_keep],
        exact=not bool(getattr(cfg.ego_motion, "enabled", False)),
    )
