"""TrackHold (evpose.tracker.track_hold): how long runs of weak registrations are reported."""

from evpose.tracker.step_result import TrackStatus
from evpose.tracker.track_hold import TrackHold

OK, DEGRADED, LOST = TrackStatus.OK, TrackStatus.DEGRADED, TrackStatus.LOST


def test_a_long_run_of_weak_registrations_is_reported_degraded_from_the_limit_on():
    hold = TrackHold(True, 0, weak_run_degraded=3)
    seen = [hold.weak_run(OK, "", weak_fused=True)[0] for _ in range(4)]
    assert seen == [OK, OK, DEGRADED, DEGRADED]
    status, reason = hold.weak_run(OK, "", weak_fused=True)
    assert status is DEGRADED and "5 updates in a row held only by weak registrations" in reason


def test_a_strict_registration_or_a_loss_ends_the_weak_run():
    hold = TrackHold(True, 0, weak_run_degraded=2)
    for _ in range(3):
        hold.weak_run(OK, "", True)
    assert hold.weak_run(OK, "", weak_fused=False) == (OK, "")
    assert hold.weak_run(OK, "", True)[0] is OK
    assert hold.weak_run(LOST, "lost", True) == (LOST, "lost") and hold.weak_streak == 0


def test_zero_limit_never_degrades_but_still_counts():
    hold = TrackHold(True, 0, weak_run_degraded=0)
    for _ in range(50):
        assert hold.weak_run(OK, "", True)[0] is OK
    assert hold.weak_streak == 50


def test_the_weak_run_survives_snapshot_and_restore_and_old_snapshots_restore():
    hold = TrackHold(True, 0, weak_run_degraded=3)
    hold.weak_run(OK, "", True), hold.weak_run(OK, "", True)
    acquisition, tracking = hold.snapshot()
    other = TrackHold(False, 0, weak_run_degraded=3)
    other.restore(acquisition, tracking)
    assert other.weak_run(OK, "", True)[0] is DEGRADED
    other.restore((True, 0), (True, 0, True))  # a snapshot from before the count
    assert other.weak_streak == 0 and other.tracking and other.never_lost
