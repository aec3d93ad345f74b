"""The events' ON leads on coarse sensors (session 33): there the ON events of crease and grazing points are taken
0.07 px behind their edge, those of plain face-on points on it; the 346x260 sensor keeps every lead as set."""

import numpy as np

from evpose.tracker.config import TrackerConfig
from evpose.tracker.event_registration_config import scaled_to_pixel
from evpose.tracker.grazing import point_leads

CAMERA = np.array([0.0, 0.0, 3.0])
"""3 m above the points, looking down."""
COARSE_MRAD, FINE_MRAD = 1e3 / 171.37776081, 1e3 / 247.06960517
"""Pixel angles of the simulated 240x180 and 346x260 cameras."""


def leads_of_the_three_classes(pixel_mrad: float):
    # 0: plain face-on ground point, 1: face-on point on a crease, 2: point of a vertical face seen edge-on (grazing).
    points = np.zeros((3, 3))
    plane = np.array([[0.0, 0, 1], [0.0, 0, 1], [1.0, 0, 0]])
    edge = np.array([[-1.0, 0, 0], [-1.0, 0, 0], [0.0, 0, -1]])  # outward normals: the camera never sees past them
    crease = np.array([False, True, False])
    config = scaled_to_pixel(TrackerConfig().event_registration, pixel_mrad)
    return point_leads(np.arange(3), crease, edge, points, plane, CAMERA, config)


def test_on_events_of_crease_and_grazing_points_are_taken_behind_their_edge_on_a_coarse_sensor():
    on, off = leads_of_the_three_classes(COARSE_MRAD)
    assert on[0] == 0.0
    assert np.allclose(on[1:], -0.07)
    c = TrackerConfig().event_registration
    assert np.allclose(off, [c.off_lead_px, c.crease_off_lead_px, c.grazing_off_lead_px])  # the OFF leads as set


def test_a_finer_sensor_and_a_config_without_it_keep_the_leads_as_set():
    on, _ = leads_of_the_three_classes(FINE_MRAD)
    assert np.array_equal(on, [0.0, 0.0, 0.0])
    c = TrackerConfig().event_registration
    assert scaled_to_pixel(c, 0.0) is c  # no pixel angle given: as configured
    c.coarse_on_lead_min_pixel_mrad = 0.0  # never
    assert scaled_to_pixel(c, COARSE_MRAD).crease_on_lead_px == c.crease_on_lead_px


def test_the_on_lead_moves_the_events_optimum_behind_the_edge():
    # One straight edge (along y through the origin, 3 m below the camera) moving +x in the image; an ON event 0.07 px
    # behind it reads zero residual with the coarse sensor's crease ON lead, 0.07 px with the lead as set (0).
    from evpose.tracker.event_registration_kernels import _linearise_events

    fx = 200.0
    pts = np.array([[0.0, 0.0, 0.0]])
    tg = np.array([[0.0, 1.0, 0.0]])
    R_cw = np.diag([1.0, -1.0, -1.0])  # camera z down
    t_cw = -R_cw @ CAMERA
    twist = np.array([0.0, 0.0, 0.0, -1.0, 0.0, 0.0])  # camera moving -x: the edge moves +x in the image
    ex, ey = np.array([100.0 - 0.07]), np.array([100.0])
    et, ep, assoc, eg = np.array([1000], np.int64), np.array([1], np.int8), np.array([0], np.int64), np.array([2 ** 62], np.int64)
    coarse = scaled_to_pixel(TrackerConfig().event_registration, COARSE_MRAD)
    res = []
    for on in (TrackerConfig().event_registration.crease_on_lead_px, coarse.crease_on_lead_px):
        H, b, sw, swr = np.zeros((6, 6)), np.zeros(6), np.empty(1), np.empty(1)
        _linearise_events(1, ex.copy(), ey.copy(), et, ep, assoc, pts, tg, R_cw, t_cw, fx, fx, 100.0, 100.0, twist, 1000,
                          np.array([on]), np.array([0.0]), eg, np.zeros(0), 0.24, 0.72, H, b, sw, swr,
                          np.zeros((0, 6)), np.zeros(0))
        res.append(swr[0] / sw[0])
    assert abs(abs(res[0]) - 0.07) < 1e-9
    assert abs(res[1]) < 1e-9
