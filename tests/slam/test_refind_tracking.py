"""The tracker re-finds a map point whose KLT track was lost, and keeps the previous MCI hypothesis when KLT fails across a switch."""

from types import SimpleNamespace

import numpy as np
import pytest

from evpose.slam import EventSlam, SlamConfig, SlamStatus
from evpose.slam.event_image import event_image, to_uint8
from evpose.slam.mci import Hypothesis, MciResult
from evpose.slam.projection_search import SearchMatcher
from slam_synthetic import make_recording


@pytest.fixture(scope="module")
def tracked_slam():
    rec = make_recording(duration_s=1.0, speed=1.5, seed=9)
    cfg = SlamConfig()
    cfg.search.enabled = True
    cfg.search.matcher = SearchMatcher.NCC  # the synthetic points keep their KLT tracks; patch search re-finds dropped ones
    # The two-view settings before session 15: with today's (homography_fit_share) this map's first pair is another
    # decomposition and one re-found point lands 1.52 px from its lost track (with session 20's face-on-plane settings
    # 1.94 px); these tests are about re-finding.
    cfg.initialization.homography_fit_share, cfg.initialization.min_parallax_deg = 0.0, 1.0
    cfg.initialization.plane_min_parallax_deg, cfg.initialization.ambiguity_rival_max_spread = 0.0, 0.0
    slam = EventSlam(cfg, rec.calibration)
    ev = rec.events
    for a in range(0, len(ev), 20000):
        slam.step(ev[a:a + 20000])
    assert slam.results[-1].status is SlamStatus.OK
    return slam


def test_re_finding_by_projection_happens_during_tracking(tracked_slam):
    refound = [int(r.reason.split("(")[1].split()[0]) for r in tracked_slam.results if r.status is SlamStatus.OK and "re-found" in r.reason]
    assert refound and sum(refound) > 0


def test_a_point_whose_track_was_lost_is_resumed_on_a_new_track(tracked_slam):
    slam = tracked_slam
    fe, m = slam.fe, slam.atlas.active
    with_point = [i for i, t in enumerate(fe.ids.tolist()) if fe.track_to_point.get(t) in m.points]
    # Drop the tracks of a few points whose templates exist, as a failed KLT step would.
    lost = [i for i in with_point if m.points[fe.track_to_point[int(fe.ids[i])]].patch is not None][:5]
    assert lost
    pids = [fe.track_to_point[int(fe.ids[i])] for i in lost]
    old_uv = fe.uv[lost].astype(np.float64)
    keep = np.ones(len(fe.ids), bool)
    keep[lost] = False
    fe.ids, fe.uv = fe.ids[keep], fe.uv[keep]
    n = slam._refind(m, SimpleNamespace(image8=fe.prev8), m.traj_T[-1], slam.cfg.search.refine_radius_px)
    assert n >= 1
    resumed = 0
    for pid, uv in zip(pids, old_uv):
        tid = m.points[pid].track_id
        if tid in set(fe.ids.tolist()) and fe.track_to_point.get(tid) == pid:
            resumed += 1
            # The new track starts where the lost one was.
            assert np.linalg.norm(fe.uv[fe.ids.tolist().index(tid)] - uv) < 1.5
    assert resumed >= 1


def _corners(shift=(0.0, 0.0), seed=0):
    rng = np.random.default_rng(seed)
    xs, ys = [], []
    for cx, cy in ((50, 40), (150, 40), (50, 120), (150, 120), (100, 80), (200, 150)):
        s = rng.uniform(0, 12, 200)
        xs += [cx + shift[0] + s[:100], np.full(100, cx + shift[0]) + rng.normal(0, 0.2, 100)]
        ys += [np.full(100, cy + shift[1]) + rng.normal(0, 0.2, 100), cy + shift[1] + s[100:]]
    return event_image(np.concatenate(xs), np.concatenate(ys), None, 240, 180, 1.0)


def test_the_previous_hypothesis_is_kept_when_klt_fails_on_the_sharpest_image():
    from evpose.core.camera import CameraCalibration

    slam = EventSlam(SlamConfig(), CameraCalibration(240, 180, 200, 200, 119.5, 89.5))
    prev = _corners()
    slam.fe.prev8, slam.fe.prev_t = to_uint8(prev), 0
    slam.fe.uv = np.array([[50, 40], [150, 40], [50, 120], [150, 120], [100, 80], [200, 150]], np.float32)
    slam.fe.ids = np.arange(6)
    slam._prev_hypothesis = "H4"
    same_look = _corners(shift=(2.0, 1.0), seed=1)
    # The "sharpest" image shows unrelated structure (as a warp of the wrong motion would): KLT loses the tracks on it.
    other = np.roll(_corners(seed=2).T, 37, axis=0).T
    mci = MciResult(10_000, other, to_uint8(other), Hypothesis.H2_SIM2, {"H2": 1.0, "H4": 0.5}, candidates={"H2": other, "H4": same_look})
    used = slam._track_mci(mci)
    assert used.hypothesis is Hypothesis.H4_NONE and np.array_equal(used.image, same_look)
    assert len(slam.fe.ids) >= 5
    # Disabled, the sharpest image is kept whatever KLT does.
    slam2 = EventSlam(SlamConfig(), CameraCalibration(240, 180, 200, 200, 119.5, 89.5))
    slam2.cfg.mci.keep_hypothesis_survival = 0.0
    slam2.fe.prev8, slam2.fe.uv, slam2.fe.ids, slam2._prev_hypothesis = to_uint8(prev), slam.fe.uv[:0].copy(), np.arange(0), "H4"
    slam2.fe.uv = np.array([[50, 40], [150, 40]], np.float32)
    slam2.fe.ids = np.arange(2)
    assert slam2._track_mci(mci).hypothesis is Hypothesis.H2_SIM2
