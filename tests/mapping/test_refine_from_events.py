"""Event-based map refinement on a synthetic painted edge whose true position is known."""

from __future__ import annotations

import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.core.contour_map import ContourMap
from evpose.core.events import EventArray
from evpose.core.trajectory import Trajectory
from evpose.mapping.refine_from_events import EventRefineConfig, measure_edge_offsets, refine_map

CAL = CameraCalibration(width=121, height=121, fx=200.0, fy=200.0, cx=60.0, cy=60.0)
TRUE_Y = 0.012
"""The painted edge lies on y = TRUE_Y of the ground plane z = 0, metres."""


def _downward_pose(x: float, y: float, z: float) -> np.ndarray:
    """Camera at (x, y, z) looking straight down (camera z = -world z, camera x = world x)."""
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = (x, y, z)
    return T


def _flight(seconds: float = 0.2, rate_hz: float = 200.0):
    """Poses of a camera 2 m up sliding along +y, and the events a sharp edge at y = TRUE_Y fires: one per
    image column, at each pixel centre the edge's projection crosses, timestamped at the crossing."""
    n = int(seconds * rate_hz) + 1
    t = np.arange(n, dtype=np.int64) * int(1e6 / rate_hz)
    cam_y = -0.05 + 0.5 * t * 1e-6  # 0.5 m/s: 50 px/s in the image at 2 m
    traj = Trajectory.from_matrices(t, np.stack([_downward_pose(0.0, y, 2.0) for y in cam_y]))
    # Image row of the edge: v = cy + fy * (-(TRUE_Y - cam_y)) / 2 (camera y = -world y); v falls as cam_y rises.
    v_of = lambda ty: CAL.cy - CAL.fy * (TRUE_Y - ty) / 2.0  # noqa: E731
    ts, xs, ys = [], [], []
    for row in range(CAL.height):
        # The edge passes row centre ``row`` when cam_y = TRUE_Y + 2 (row - cy) / fy.
        cy_cross = TRUE_Y + 2.0 * (row - CAL.cy) / CAL.fy
        tc = (cy_cross + 0.05) / 0.5 * 1e6
        if not (t[0] < tc < t[-1]):
            continue
        assert abs(v_of(cy_cross) - row) < 1e-9
        for col in range(10, CAL.width - 10):
            ts.append(int(round(tc)) + (col % 7))  # a few us of spread, as a sensor's latency would add
            xs.append(col)
            ys.append(row)
    order = np.argsort(ts, kind="stable")
    ev = EventArray.from_arrays(np.asarray(ts)[order], np.asarray(xs)[order], np.asarray(ys)[order], np.ones(len(ts)))
    return ev, traj


def _edge_map(y0: float, curvature: float = 0.0005) -> ContourMap:
    """Points every 1 cm along x on y = y0, edge normal +y, plane normal up."""
    x = np.arange(-0.2, 0.2001, 0.01)
    n = x.size
    pts = np.stack([x, np.full(n, y0), np.zeros(n)], axis=1)
    return ContourMap.from_points(
        pts, edge_normal=np.tile([0.0, 1.0, 0.0], (n, 1)), plane_normal=np.tile([0.0, 0.0, 1.0], (n, 1)),
        region_id=np.zeros(n), curvature=np.full(n, curvature), brightness_sign=np.ones(n))


def test_refine_moves_a_shifted_edge_back_onto_the_events():
    events, traj = _flight()
    cmap = _edge_map(0.0)  # 12 mm (1.2 px) off the true edge
    offsets = measure_edge_offsets(events, traj, traj.t, CAL, cmap, EventRefineConfig())
    result = refine_map(cmap, offsets)
    inner = np.abs(cmap.points[:, 0]) < 0.15  # the outer points leave the image for part of the flight
    assert result.moved[inner].all()
    # Pixel centres every 10 mm along y quantise each event; the mean over the flight lands within a few mm.
    np.testing.assert_allclose(result.contour_map.points[inner, 1], TRUE_Y, atol=0.003)
    np.testing.assert_allclose(result.contour_map.points[:, [0, 2]], cmap.points[:, [0, 2]])


def test_refine_keeps_a_point_that_is_already_on_the_edge():
    events, traj = _flight()
    cmap = _edge_map(TRUE_Y)
    result = refine_map(cmap, measure_edge_offsets(events, traj, traj.t, CAL, cmap, EventRefineConfig()))
    assert np.max(np.abs(result.shift_m)) < 0.003


def test_refine_leaves_crease_points_alone():
    events, traj = _flight()
    cmap = _edge_map(0.0, curvature=0.05)  # a plane intersection: trusted as built
    result = refine_map(cmap, measure_edge_offsets(events, traj, traj.t, CAL, cmap, EventRefineConfig()))
    assert not result.moved.any()
    np.testing.assert_array_equal(result.contour_map.points, cmap.points)


def test_refine_uses_only_registered_updates():
    events, traj = _flight()
    cmap = _edge_map(0.0)
    offsets = measure_edge_offsets(events, traj, np.zeros(0, np.int64), CAL, cmap, EventRefineConfig())
    assert offsets.histogram.sum() == 0
    assert not refine_map(cmap, offsets).moved.any()


def test_refine_is_deterministic():
    events, traj = _flight()
    cmap = _edge_map(0.0)
    a = refine_map(cmap, measure_edge_offsets(events, traj, traj.t, CAL, cmap))
    b = refine_map(cmap, measure_edge_offsets(events, traj, traj.t, CAL, cmap))
    np.testing.assert_array_equal(a.contour_map.points, b.contour_map.points)
