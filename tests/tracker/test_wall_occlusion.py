"""Wall feet: found from the map's own regions, hidden only when the camera looks at them over their wall."""

import evpose  # noqa: F401  (BLAS pin before numpy)

import numpy as np

from evpose.core.contour_map import ContourMap
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.wall_occlusion import hidden_by_walls, wall_foot_mask


def _step_map(height=0.15):
    """A 1 m ground edge at x = 0 (ground region 0 on x < 0, edge normal +x towards a step), the step's rim
    ``height`` above it (region 1, edge normal -x), and a free ground edge at x = -2 with nothing above it."""
    y = np.linspace(-0.5, 0.5, 21)
    foot = np.c_[np.zeros_like(y), y, np.zeros_like(y)]
    rim = np.c_[np.full_like(y, 0.04), y, np.full_like(y, height)]  # built maps put the rim a few cm inside
    free = np.c_[np.full_like(y, -2.0), y, np.zeros_like(y)]
    pts = np.vstack([foot, rim, free])
    n = len(y)
    en = np.vstack([np.tile([1.0, 0, 0], (n, 1)), np.tile([-1.0, 0, 0], (n, 1)), np.tile([-1.0, 0, 0], (n, 1))])
    pn = np.tile([0.0, 0, 1.0], (3 * n, 1))
    rid = np.r_[np.zeros(n), np.ones(n), np.zeros(n)].astype(np.int32)
    return ContourMap.from_points(pts, edge_normal=en.astype(np.float32), plane_normal=pn.astype(np.float32), region_id=rid), n


def test_only_the_foot_under_another_region_is_a_wall_foot():
    cmap, n = _step_map()
    m = wall_foot_mask(cmap, 0.06, 0.06, 0.05, 0.8)
    assert m[:n].all()
    assert not m[n:].any()  # the rim (nothing above it) and the free edge
    assert not wall_foot_mask(cmap, 0.06, 0.06, 0.3, 0.8).any()  # lower than the smallest wall looked for (+ radius)


def test_the_foot_is_hidden_only_from_the_wall_side():
    cmap, n = _step_map()
    m = wall_foot_mask(cmap, 0.06, 0.06, 0.05, 0.8)
    P, E = np.asarray(cmap.points, float), np.asarray(cmap.edge_normal, float)
    idx = np.arange(len(cmap))
    over_wall = hidden_by_walls(P, E, m, idx, np.array([1.0, 0.0, 4.0]))
    assert over_wall[:n].all() and not over_wall[n:].any()
    facing = hidden_by_walls(P, E, m, idx, np.array([-1.0, 0.0, 4.0]))
    assert not facing.any()


def test_the_mask_is_cached_read_only_and_deterministic():
    cmap, _ = _step_map()
    a = wall_foot_mask(cmap, 0.06, 0.06, 0.05, 0.8)
    b = wall_foot_mask(_step_map()[0], 0.06, 0.06, 0.05, 0.8)
    assert a is b and not a.flags.writeable


def test_tracker_drops_hidden_feet_in_stpe_but_not_in_the_fused_modes_by_default():
    from evpose.core.camera import CameraCalibration
    from evpose.tracker.tracker import Tracker

    cmap, n = _step_map()
    cal = CameraCalibration(240, 180, 200.0, 200.0, 119.5, 89.5)
    stpe = Tracker(TrackerConfig(mode=TrackerMode.STPE), cmap, cal)
    assert stpe._wall_feet is not None and stpe._wall_feet[:n].all()
    off = TrackerConfig(mode=TrackerMode.STPE)
    off.visible_map.wall_occlusion = False
    assert Tracker(off, cmap, cal)._wall_feet is None
    from evpose.tracker.modes import MotionComponents

    fused = Tracker(TrackerConfig(mode=TrackerMode.STPE), cmap, cal, components=MotionComponents(drives_pose=True))
    assert fused._wall_feet is None  # fused_wall_occlusion is off by default
