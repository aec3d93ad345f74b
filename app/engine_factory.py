"""Which engine the viewer runs for a recording, a map and a mode: tracker, events-only view or SLAM."""

from __future__ import annotations

from app.engine import EventsOnlyEngine
from app.frame_cache import FrameCacheConfig
from app.slam_engine import slam_engine_factory
from app.tracker_engine import TrackerEngine
from evpose.errors import EvposeError

NO_MAP_NOTE = "No contour map selected: showing events and time surfaces only. Tracking needs a map of the scene."


MODES = ("tracking", "slam")
"""Viewer modes: EV-Pose tracking against a map, or map-free event SLAM (``evpose.slam``)."""


def engine_factory(recording, contour_map, mode: str = "tracking", cache: FrameCacheConfig | None = None):
    """A config -> Engine function for this recording/map pair, with the reason when tracking is impossible."""
    if mode == "slam":
        return slam_engine_factory(recording)
    if contour_map is None:
        return lambda cfg: EventsOnlyEngine(recording, cfg, explanation=NO_MAP_NOTE)
    try:
        import evpose.tracker.session  # noqa: F401
    except ImportError as exc:
        note = f"The tracker is not available in this build ({exc}); showing events only."
        return lambda cfg: EventsOnlyEngine(recording, cfg, explanation=note)

    def make(cfg):
        try:
            return TrackerEngine(recording, contour_map, cfg, cache=cache)
        except EvposeError as exc:
            # Still show events and time surfaces, and say why tracking cannot run.
            return EventsOnlyEngine(recording, None, explanation=f"Tracking cannot start: {exc}")

    return make
