"""The painted-edge refiner's own gain in the fused modes (``MapRefinementConfig.fused_gain``): where a fusion drives
the pose the refiner moves painted points by that share of each step, elsewhere (and at 0) by ``gain``."""

import numpy as np
from test_map_refinement import DOWN, K, line_field, painted_line

from evpose.core.camera import CameraCalibration
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.modes import MotionComponents
from evpose.tracker.tracker import Tracker

W = 120


def _calibration() -> CameraCalibration:
    return CameraCalibration(W, 90, K[0, 0], K[1, 1], K[0, 2], K[1, 2])


def _refiner(fused_gain: float, drives_pose: bool, gain: float = 0.05):
    cfg = TrackerConfig(mode=TrackerMode.FULL if drives_pose else TrackerMode.STPE)
    cfg.map_refinement.gain = gain
    cfg.map_refinement.fused_gain = fused_gain
    cfg.map_refinement.first_updates = 0  # the fixed gain from the first update
    comps = MotionComponents(drives_pose=True) if drives_pose else None
    return Tracker(cfg, painted_line(0.02), _calibration(), components=comps).refiner


def _first_move(refiner) -> float:
    """How far (m) the first painted point moves in one update towards a field whose edge is 1 px (2 cm) left of it."""
    pts = np.array(painted_line(0.02).points)
    before = pts[0, 0]
    assert refiner.update(pts, line_field((W - 1) / 2), DOWN, K) > 0
    return float(before - pts[0, 0])


def test_the_fused_modes_refine_painted_edges_with_their_own_gain():
    fused = _refiner(0.03, drives_pose=True)
    assert fused.config.gain == 0.03
    unfused = _refiner(0.03, drives_pose=False)
    assert unfused.config.gain == 0.05  # stpe keeps ``gain``
    assert _refiner(0.0, drives_pose=True).config.gain == 0.05  # 0 = ``gain``
    # The same clipped step, taken by each gain's share: the fused point moves 0.03 / 0.05 as far, towards the edge.
    m_fused, m_unfused = _first_move(fused), _first_move(unfused)
    assert m_fused > 0 and m_unfused > 0
    np.testing.assert_allclose(m_fused / m_unfused, 0.03 / 0.05, rtol=1e-9)
