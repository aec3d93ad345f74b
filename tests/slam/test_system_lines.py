"""Line landmarks inside the SLAM system: a starved event-only map is placed on its 3-D lines instead of coasting, the
PnP-placed MCIs feed the line tracks, and the line state follows snapshots."""

from types import SimpleNamespace

import cv2
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam import EventSlam, SlamConfig, SlamStatus
from evpose.slam.event_coasting import event_only_coast_pose
from evpose.slam.line_landmarks import LineMap, LineTrack, project_segment
from slam_synthetic import make_recording


@pytest.fixture(scope="module")
def early_map():
    return make_recording(duration_s=0.4, speed=1.5, seed=7, shake=0.08)


def _run(rec, lines: bool) -> EventSlam:
    cfg = SlamConfig()
    cfg.lines.enabled = lines
    slam = EventSlam(cfg, rec.calibration)
    slam.step(rec.events)
    assert slam.atlas.active is not None and len(slam.atlas.active.traj_t) >= 3
    return slam


def _lines_in_front(T_wc: np.ndarray, depth: float) -> list[np.ndarray]:
    """Three vertical 3-D segments (camera frame x -0.3 / 0.05 / 0.35 of the depth, at 0.8 / 1 / 1.3 of it), in the world."""
    out = []
    for x, z in ((-0.3, 0.8), (0.05, 1.0), (0.35, 1.3)):
        Xc = np.array([[x * depth, -0.3 * depth, z * depth], [x * depth, 0.3 * depth, z * depth]])
        out.append(Xc @ T_wc[:3, :3].T + T_wc[:3, 3])
    return out


def _draw(slam, T_wc: np.ndarray, segments: list[np.ndarray]) -> np.ndarray:
    img = np.zeros((slam.height, slam.width), np.float32)
    for X in segments:
        p = project_segment(slam.K, invert_pose(T_wc), X)
        cv2.line(img, (int(round(p[0] * 16)), int(round(p[1] * 16))), (int(round(p[2] * 16)), int(round(p[3] * 16))), 1.0, 1, cv2.LINE_AA, shift=4)
    img = cv2.GaussianBlur(img, (0, 0), 1.0)
    return (255.0 * img / img.max()).astype(np.uint8)


def _starved_mci(slam):
    m = slam.atlas.active
    t = m.traj_t[-1] + 4000
    T_pred = event_only_coast_pose(m, t, int(slam.cfg.tracking.coast_span_s * 1e6))
    depth = float(np.median((m.point_array() - T_pred[:3, 3]) @ T_pred[:3, 2]))
    segments = _lines_in_front(T_pred, depth)
    lm = slam._line_map(m)
    lm.tracks = [LineTrack(i, project_segment(slam.K, invert_pose(T_pred), X), invert_pose(T_pred), X=X) for i, X in enumerate(segments)]
    return m, T_pred, SimpleNamespace(t_us=t, image8=_draw(slam, T_pred, segments))


def test_a_starved_map_is_placed_on_its_lines_only_when_they_are_on(early_map):
    for enabled, expected in ((False, SlamStatus.COASTING), (True, SlamStatus.OK)):
        slam = _run(early_map, enabled)
        m, T_pred, mci = _starved_mci(slam)
        status, reason, pose, _ = slam._bridge_or_lose(mci, "no tracks")
        assert status is expected, reason
        if enabled:
            assert reason.startswith("line-tracked: 3 lines") and slam._last_visual_t == mci.t_us and m.traj_t[-1] == mci.t_us
            # The lines sit where the prediction puts them, so the pose stays there.
            assert np.degrees(Rotation.from_matrix(pose[:3, :3].T @ T_pred[:3, :3]).magnitude()) < 0.2
            depth = float(np.median((m.point_array() - T_pred[:3, 3]) @ T_pred[:3, 2]))
            assert np.linalg.norm(pose[:3, 3] - T_pred[:3, 3]) < 0.01 * depth


def test_a_blank_mci_is_not_line_tracked(early_map):
    slam = _run(early_map, True)
    m, _, mci = _starved_mci(slam)
    mci.image8 = np.zeros_like(mci.image8)
    status, _, _, _ = slam._bridge_or_lose(mci, "no tracks")
    assert status is SlamStatus.COASTING


def test_placed_mcis_feed_line_tracks_and_snapshots_keep_them(early_map):
    slam = _run(early_map, True)
    m, T_pred, mci = _starved_mci(slam)
    slam._lines = LineMap()
    slam._lines_after_pose(m, mci, T_pred)
    assert slam._lines.map_id == m.id and len(slam._lines.tracks) == 3
    snap = slam.snapshot()
    n = len(slam._lines.tracks)
    slam._lines = LineMap()
    slam.restore(snap)
    assert len(slam._lines.tracks) == n
    off = _run(early_map, False)
    off._lines_after_pose(m, mci, T_pred)
    assert len(off._lines.tracks) == 0


def test_refine_pnp_keeps_a_pose_its_points_and_lines_agree_with(early_map):
    from evpose.slam.geometry import project

    slam = _run(early_map, True)
    m, T_pred, mci = _starved_mci(slam)
    pids = sorted(m.points)[:20]
    uv, _ = project(slam.K, invert_pose(T_pred), np.stack([m.points[p].xyz for p in pids]))
    fe = slam.fe
    fe.ids = np.arange(1000, 1000 + len(pids), dtype=np.int64)
    fe.uv = uv.astype(np.float32)
    fe.track_to_point = {1000 + i: p for i, p in enumerate(pids)}
    same, segs = slam._pnp_pose_with_lines(m, mci, T_pred, list(range(len(pids))))
    assert same is T_pred and segs is None  # refine_pnp is off by default
    slam.cfg.lines.refine_pnp = True
    pose, segs = slam._pnp_pose_with_lines(m, mci, T_pred, list(range(len(pids))))
    assert len(segs) == 3
    # Within the sub-pixel error of the drawn lines (0.3 deg is 1.3 px at this focal length).
    assert np.degrees(Rotation.from_matrix(pose[:3, :3].T @ T_pred[:3, :3]).magnitude()) < 0.3
