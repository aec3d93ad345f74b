"""Whether the tracker holds the map: acquisition before the fused modes' loose inlier test, and ``stpe``'s
rule for regaining a lost track.

Both are counters of registrations in a row that passed the strict inlier test. A wrong map (or a wrong lock)
passes a loose test now and then, but seldom several strict ones in a row.
"""

from __future__ import annotations

import numpy as np

from evpose.tracker.step_result import TrackStatus

ACQUIRE_UPDATES = 5
"""Registrations in a row that must pass the strict inlier test before the fused modes' looser one applies."""


class TrackHold:
    """Acquisition and regain bookkeeping of one :class:`~evpose.tracker.tracker.Tracker`."""

    def __init__(self, acquired: bool, regain_updates: int, weak_run_degraded: int = 0) -> None:
        self.acquired = bool(acquired)
        """The map is acquired: the fused modes' looser inlier test applies from now on."""
        self.strict_streak = 0
        self.tracking = True
        """The track is held (``stpe``'s weak-registration test applies only then)."""
        self.regain_streak = 0
        self.never_lost = True
        """No update was lost since :meth:`start` (weak registrations and map refinement count only then)."""
        self.regain_updates = int(regain_updates)
        """Strict registrations in a row that regain a lost track (0 = a lost track is never regained)."""
        self.weak_streak = 0
        """Updates in a row held only by weak registrations (fused because they agreed with the motion model)."""
        self.weak_run_degraded = int(weak_run_degraded)
        """From this many such updates on, they are reported degraded (0 = never)."""

    def start(self) -> None:
        self.tracking, self.regain_streak, self.never_lost, self.weak_streak = True, 0, True, 0

    def snapshot(self) -> tuple:
        return (self.acquired, self.strict_streak), (self.tracking, self.regain_streak, self.never_lost, self.weak_streak)

    def restore(self, acquisition: tuple, tracking: tuple = (True, 0, True, 0)) -> None:
        self.acquired, self.strict_streak = acquisition
        # Snapshots written before the weak-run count (the viewer's disk cache) hold three values.
        self.tracking, self.regain_streak, self.never_lost, self.weak_streak = (*tracking, 0)[:4]

    def acquisition_test(self, inliers: int, points_used: int, min_inlier_ratio: float) -> str:
        """Before the map is acquired, a registration must pass the strict inlier test; '' when it does."""
        need = float(min_inlier_ratio) * points_used
        if inliers >= need:
            self.strict_streak += 1
            self.acquired = self.strict_streak >= ACQUIRE_UPDATES
            return ""
        self.strict_streak = 0
        return (f"acquiring the map: only {inliers} of {points_used} map points lie on recent events "
                f"(need {int(np.ceil(need))} until {ACQUIRE_UPDATES} updates in a row have them)")

    def regain(self, status: TrackStatus, reason: str, strict_ok: bool) -> tuple[TrackStatus, str]:
        """``stpe``'s weak-registration test: a lost track is held again only after ``regain_updates``
        registrations in a row pass the strict inlier test (0 = never); until then they are fused but the update
        is still reported lost (a candidate lock, not a pose to write out)."""
        if status is TrackStatus.LOST:
            self.tracking, self.regain_streak = False, 0
            return status, reason
        if self.tracking:
            return status, reason
        need = self.regain_updates
        if not (strict_ok and status is TrackStatus.OK):
            self.regain_streak = 0
            return TrackStatus.LOST, reason or "the track was lost: the registration was not fused"
        self.regain_streak += 1
        if need > 0 and self.regain_streak >= need:
            self.tracking = True
            return status, reason
        if need <= 0:
            return TrackStatus.LOST, "the track was lost and is not regained (registration.regain_updates = 0)"
        return TrackStatus.LOST, (f"re-acquiring the track: {self.regain_streak} of {need} registrations in a "
                                  f"row passed the strict inlier test")

    def weak_run(self, status: TrackStatus, reason: str, weak_fused: bool) -> tuple[TrackStatus, str]:
        """The status ``stpe`` reports: an OK update held only by a weak registration is degraded once
        ``weak_run_degraded`` of them came in a row. The tracker's own bookkeeping (learning, regain) keeps the OK:
        this is what the update says about itself, not a change to the track."""
        self.weak_streak = self.weak_streak + 1 if (weak_fused and status is TrackStatus.OK) else 0
        if status is TrackStatus.OK and 0 < self.weak_run_degraded <= self.weak_streak:
            return TrackStatus.DEGRADED, (f"{self.weak_streak} updates in a row held only by weak registrations (under the "
                                          f"strict inlier share): the pose follows the motion model")
        return status, reason
