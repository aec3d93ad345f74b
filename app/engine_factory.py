"""Which engine the viewer runs for a recording, a map and a mode: tracker, events-only view or SLAM."""

from __future__ import annotations

from pathlib import Path

from app.disk_cache import DiskCache, DiskCacheConfig, cache_key, source_hash
from app.engine import EventsOnlyEngine
from app.frame_cache import FrameCacheConfig
from app.slam_engine import slam_engine_factory
from app.tracker_engine import TrackerEngine
from evpose.errors import EvposeError, interrupt_cause

NO_MAP_NOTE = "No contour map selected: showing events and time surfaces only. Tracking needs a map of the scene."


CLI_MODE_HINT = "(use --mode stpe)"
"""How the tracker says which mode runs without an IMU (evpose/tracker/modes.py), in command-line words ..."""
GUI_MODE_HINT = "(set **mode** to stpe in the parameters below)"
"""... and in the viewer's."""

MODES = ("tracking", "slam")
"""Viewer modes: EV-Pose tracking against a map, or map-free event SLAM (``evpose.slam``)."""


def disk_entry_maker(disk: DiskCacheConfig | None, recording_path: Path | None, map_path: Path | None):
    """``(config, every_steps) -> DiskCache`` for this recording/map pair, or None when there is no disk cache."""
    if disk is None or not disk.enabled or recording_path is None or map_path is None:
        return None
    try:
        sources = source_hash()  # once per opening: the code does not change under a running engine
    except OSError:
        return None

    def entry(config, every_steps: int) -> DiskCache | None:
        try:
            key, parts = cache_key(recording_path, map_path, config, every_steps, sources)
        except OSError:  # the files went away since they were opened: nothing to key on
            return None
        return DiskCache(disk, key, parts)

    return entry


def engine_factory(recording, contour_map, mode: str = "tracking", cache: FrameCacheConfig | None = None,
                   disk: DiskCacheConfig | None = None, paths: tuple[Path, Path] | None = None):
    """A config -> Engine function for this recording/map pair, with the reason when tracking is impossible.

    ``disk`` and the pair's file ``paths`` turn on the persistent cache of the tracker's run-ahead.
    """
    if mode == "slam":
        return slam_engine_factory(recording)
    if contour_map is None:
        return lambda cfg: EventsOnlyEngine(recording, cfg, explanation=NO_MAP_NOTE)
    try:
        import evpose.tracker.session  # noqa: F401
    except ImportError as exc:
        # A Ctrl+C or SIGTERM landing while gtsam/open3d import fails the import ("initialization failed"): `evpose
        # app --prepare` then said "the tracker is not available in this build" and exited 2 (session 31, 1 of 3
        # SIGTERMs 3 s in). The user asked to stop.
        interrupt = interrupt_cause(exc, swallowed=True)
        if interrupt is not None:
            raise interrupt from None
        note = f"The tracker is not available in this build ({exc}); showing events only."
        return lambda cfg: EventsOnlyEngine(recording, cfg, explanation=note)

    from evpose.tracker.config import TrackerConfig

    entry = disk_entry_maker(disk, *(paths or (None, None)))

    def make(cfg):
        try:
            return TrackerEngine(recording, contour_map, cfg, cache=cache, disk=entry)
        except EvposeError as exc:
            # Still show events and time surfaces, and say why tracking cannot run.
            why = str(exc)
            by_mode = CLI_MODE_HINT in why
            fallback = EventsOnlyEngine(recording, None, explanation=f"Tracking cannot start: {why.replace(CLI_MODE_HINT, GUI_MODE_HINT)}",
                                        cause=exc)
            # The tracker's controls stay (or come) when a parameter can change the outcome: the user's tuned ones,
            # or the defaults when the mode is the cause. A recording without IMU opened first showed the
            # events-only view's controls and "use --mode stpe", a command-line flag: no control could set it.
            fallback.rejected_config = cfg if isinstance(cfg, TrackerConfig) else (TrackerConfig() if by_mode else None)
            return fallback

    return make
