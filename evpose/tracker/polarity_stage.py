"""The tracker's side of the polarity event filter (issue 7, EV-Pose MHFO early stage): ``T_align`` composed before
registration (:mod:`evpose.fusion.aligned_surface`), the step's events labelled and the points' signs learned after
the pose.

Called by :meth:`Tracker.step <evpose.tracker.tracker.Tracker.step>` when its ``polarity_selector`` supports them
(:class:`~evpose.fusion.map_polarity_selector.MapPolaritySelector`).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import numpy as np

from evpose.fusion.aligned_surface import AlignedTimeSurface
from evpose.tracker.step_result import elapsed_ms

if TYPE_CHECKING:
    from evpose.tracker.tracker import Tracker


def align_to_polarity(tracker: Tracker, used: np.ndarray, pts: np.ndarray, polarity: np.ndarray, skip: np.ndarray | None,
                      predicted: np.ndarray, roi, events, keep: np.ndarray, until: int, counts: dict) -> tuple:
    """``(T_align, with_events)`` for the points ``used`` (``pts`` their positions, ``polarity`` their predicted
    polarity) at the predicted ``T_world_cam``, or ``(None, None)`` when the selector composes none.

    ``with_events`` (bool over ``used``, None: all) are the points registration is to read: not those whose patch
    shows no recent event of their polarity, nor held-out painted points (``skip``, bool over the map). ``T_align``'s
    counts are added to ``counts``.
    """
    box = tracker._field_box(pts, predicted, True) if tracker.coarse_field is not None else roi
    aligned = tracker.polarity_selector.align(tracker.time_surface, pts, predicted, polarity, box, events, keep, until)
    if aligned is None:
        return None, None
    counts.update(aligned.last_counts)
    with_events = tracker.polarity_selector.points_to_register()
    if skip is not None:
        ready = ~np.take(skip, used)
        with_events = ready if with_events is None else with_events & ready
    return aligned, with_events


def learn_polarity_signs(tracker: Tracker, events, keep: np.ndarray, composed: tuple, polarity: np.ndarray, surface,
                         counts: dict, timings: dict) -> None:
    """The polarity filter's pass after the pose: label the step's ``events`` (``keep``: those the noise filters kept)
    against the points ``composed`` (map indices, predicted polarity) and learn point signs from them.

    ``surface`` is what registration read (``T_align`` when the event filter composed one).
    """
    # Label this step's events against the prediction (reports, viewer) and learn point signs from them.
    t0 = time.perf_counter()
    labels = tracker.polarity_selector.observe(events, tracker._pose, *composed, tracker.width, tracker.height, keep=keep)
    if isinstance(surface, AlignedTimeSurface):  # its event pass (labels, counts) waited for the pose: see align
        surface.judge()
        counts.update({k: v for k, v in surface.last_counts.items() if k.startswith("events_")})
    counts.setdefault("events_polarity_removed", int(np.count_nonzero(labels == 0)))  # T_align's count if it ran
    counts["points_single_polarity"] = int(np.count_nonzero(polarity))
    timings["polarity_observe"] = elapsed_ms(t0)
    timings["polarity_filter"] = timings.get("polarity_filter", 0.0) + timings["polarity_observe"]
