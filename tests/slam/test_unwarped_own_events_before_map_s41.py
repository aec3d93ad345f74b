"""``MciConfig.unwarped_own_events_before_map``: event-only runs render H4 from each window's own events while no map is
tracked, and from the whole window once one is."""

from evpose.slam import SlamConfig, SlamStatus, run_slam
from evpose.slam.config import SlamMode
from evpose.slam.system import EventSlam
from slam_synthetic import make_recording


def _calls(before_map: bool, mode: SlamMode = SlamMode.EVENT) -> list[tuple[SlamStatus, int, int]]:
    cfg = SlamConfig()
    cfg.mci.unwarped_own_events_before_map = before_map
    cfg.mode = mode
    rec = make_recording(duration_s=0.6, speed=1.5, seed=3)
    slam = EventSlam(cfg, rec.calibration, rec.imu)
    seen = []
    gen = slam.mci_gen.generate

    def spy(rw, prior=None, mapped=True):
        res = gen(rw, prior, mapped)
        # (state, events rendered into H4, events in the window)
        own = res.splats["H4"].x.size
        seen.append((slam._state, own, len(rw.t) if rw.n_overlap else own))
        return res

    slam.mci_gen.generate = spy
    run_slam(rec, cfg, slam=slam)
    return seen


def test_off_by_default_and_then_every_h4_holds_its_whole_window():
    assert SlamConfig().mci.unwarped_own_events_before_map is False
    assert all(own == n for _, own, n in _calls(False))


def test_on_only_the_mcis_before_a_map_is_tracked_render_their_own_events():
    seen = _calls(True)
    assert any(s is SlamStatus.OK for s, _, _ in seen) and any(s is not SlamStatus.OK and own < n for s, own, n in seen)
    assert all((own < n) == (s is not SlamStatus.OK) for s, own, n in seen if own != n or s is SlamStatus.OK)


def test_event_inertial_runs_never_render_own_events():
    assert all(own == n for _, own, n in _calls(True, SlamMode.EVENT_INERTIAL))
