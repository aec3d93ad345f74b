"""``InitializationConfig.restart_at_failed_mci``: a two-view attempt that gives up its reference makes the failing MCI
the new reference at once (off: the next MCI becomes it)."""

from evpose.slam import SlamConfig, SlamStatus, run_slam
from slam_synthetic import make_recording


def _init_reasons(restart: bool) -> list[tuple[int, str]]:
    cfg = SlamConfig()
    cfg.initialization.min_matches = 100_000  # every attempt fails for too few matches and gives up its reference
    cfg.initialization.restart_at_failed_mci = restart
    run = run_slam(make_recording(duration_s=0.6, speed=1.5, seed=3), cfg)
    assert all(r.status is SlamStatus.NOT_INITIALISED for r in run.results)
    return [(r.t_us, r.reason) for r in run.results]


def test_off_by_default():
    assert SlamConfig().initialization.restart_at_failed_mci is False


def test_off_the_mci_after_a_given_up_reference_becomes_the_next_reference():
    reasons = [r for _, r in _init_reasons(False)]
    assert len(reasons) >= 6
    # reference, attempt, reference, attempt, ...: every other MCI only sets a reference
    assert all(("reference set with" in r) == (i % 2 == 0) for i, r in enumerate(reasons))


def test_on_the_failing_mci_is_the_new_reference_so_every_later_mci_is_an_attempt():
    reasons = [r for _, r in _init_reasons(True)]
    assert len(reasons) >= 6
    assert reasons[0].startswith("initialisation reference set with")
    assert all(r.startswith("initialisation: ") and "; reference set again with" in r for r in reasons[1:])
