"""Which points' surfaces are seen at a grazing angle or sit on a crease, the field's extra OFF trail and the events'
leads they take."""

import numpy as np

from evpose.tracker.config import TrackerConfig
from evpose.tracker.grazing import add_crease_off_trail, add_grazing_off_trail, crease_points, grazing_points, point_leads

NORMALS = np.array([[0.0, 0, 1], [1.0, 0, 0], [0.0, 0, 0], [0.0, 0.6, 0.8]])
"""Seen from 2 m above the origin: |cos| 1 (face-on), 0 (edge-on), unknown, 0.8."""
POINTS = np.zeros((4, 3))
ABOVE = np.array([0.0, 0, 2])


def test_grazing_points_are_those_seen_edge_on_and_never_those_without_a_normal():
    assert grazing_points(NORMALS, POINTS, ABOVE, 0.6).tolist() == [False, True, False, False]
    assert grazing_points(NORMALS, POINTS, ABOVE, 0.9).tolist() == [False, True, False, True]


def trail_of(max_cos: float, extra_px: float) -> np.ndarray:
    used = np.array([1, 0, 3])  # edge-on, face-on, grazing at max_cos 0.9
    polarity = np.array([-1, -1, 1], np.int8)  # OFF, OFF, ON
    cfg = TrackerConfig()
    cfg.event_registration.grazing_max_cos = max_cos
    cfg.registration.fused_grazing_off_trail_px = extra_px
    trail = np.full(3, 0.1)
    add_grazing_off_trail(trail, polarity, NORMALS, used, POINTS[used], ABOVE, cfg)
    return trail


def test_only_grazing_off_points_trail_further():
    assert np.allclose(trail_of(0.9, 0.2), [0.3, 0.1, 0.1])


def test_no_extra_trail_when_either_setting_is_zero():
    assert np.array_equal(trail_of(0.0, 0.2), np.full(3, 0.1))
    assert np.array_equal(trail_of(0.9, 0.0), np.full(3, 0.1))


def test_crease_points_are_those_beside_another_regions_surface_at_an_angle():
    # A box's top (region 0, normal +z) meeting its side (region 1, normal +x) at x = 0; a coplanar ground panel
    # (region 2, normal +z) beside the top's far edge; a lone point of the top's own region.
    points = np.array([[0.0, 0, 0], [0.005, 0, 0], [0.3, 0, 0], [0.31, 0, 0], [0.6, 0, 0], [0.605, 0, 0]])
    normals = np.array([[0.0, 0, 1], [1.0, 0, 0], [0.0, 0, 1], [0.0, 0, 1], [0.0, 0, 1], [0.0, 0, 0]])
    region = np.array([0, 1, 0, 2, 0, 3])
    assert crease_points(points, normals, region, 0.02).tolist() == [True, True, False, False, False, False]
    assert not crease_points(points, normals, region, 0.0).any()


def crease_trail_of(extra_px: float, crease) -> np.ndarray:
    used = np.array([1, 0, 0, 3])  # edge-on (grazing), face-on, face-on, |cos| 0.8
    polarity = np.array([-1, -1, 1, -1], np.int8)  # OFF, OFF, ON, OFF
    cfg = TrackerConfig()
    cfg.event_registration.grazing_max_cos = 0.6
    cfg.registration.fused_crease_off_trail_px = extra_px
    trail = np.full(4, 0.1)
    add_crease_off_trail(trail, polarity, crease, NORMALS, used, POINTS[used], ABOVE, cfg)
    return trail


def test_face_on_off_points_trail_further_on_a_crease_and_less_elsewhere():
    crease = np.array([True, True, False, False])  # points 0 and 1 on a crease
    assert np.allclose(crease_trail_of(0.2, crease), [0.1, 0.2, 0.1, 0.0])
    assert np.array_equal(crease_trail_of(0.0, crease), np.full(4, 0.1))
    assert np.array_equal(crease_trail_of(0.2, None), np.full(4, 0.1))


def numpy_leads(used, crease, edge_normals, points, plane_normals, centre, c):
    """The events' leads as numpy masks (what :func:`point_leads` does in one compiled pass)."""
    on, off = np.full(used.size, c.on_lead_px), np.full(used.size, c.off_lead_px)
    if crease is not None:
        k = crease[used]
        on[k], off[k] = c.crease_on_lead_px, c.crease_off_lead_px
        off[~k & (np.einsum("ij,ij->i", edge_normals[used], centre - points[used]) > 0)] = c.beyond_off_lead_px
    if c.grazing_max_cos > 0 and plane_normals is not None:
        g = grazing_points(plane_normals, points, centre, c.grazing_max_cos, used)
        on[g], off[g] = c.grazing_on_lead_px, c.grazing_off_lead_px
    return on, off


def test_point_leads_give_each_class_its_lead_as_the_numpy_masks_do():
    rng = np.random.default_rng(3)
    n = 400
    points = rng.normal(size=(n, 3))
    edge = rng.normal(size=(n, 3))
    edge /= np.linalg.norm(edge, axis=1, keepdims=True)
    plane = rng.normal(size=(n, 3)).astype(np.float32)
    plane /= np.linalg.norm(plane, axis=1, keepdims=True)
    plane[::7] = 0.0  # unknown normals are never grazing
    crease = rng.random(n) < 0.2
    used = np.sort(rng.choice(n, 150, replace=False))
    centre = np.array([0.1, -0.2, 3.0])
    c = TrackerConfig().event_registration
    c.on_lead_px, c.crease_on_lead_px, c.grazing_on_lead_px = 0.05, 0.07, 0.09  # every class distinct
    for max_cos, cr, pl in ((0.6, crease, plane), (0.0, crease, plane), (0.6, None, plane), (0.6, crease, None)):
        c.grazing_max_cos = max_cos
        got = point_leads(used, cr, edge, points, pl, centre, c)
        want = numpy_leads(used, cr, edge, points, pl, centre, c)
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    assert len(set(got[1].tolist())) == 3  # plain, crease and beyond leads all present (grazing off above)
