"""The covered-foot OFF lead (evpose.tracker.covered_feet, EventRegistrationConfig.covered_foot_off_lead_px): which map
points are a vertical face's foot, and when the face's image lies behind the foot along its motion."""

import dataclasses

import numpy as np

from evpose.tracker.covered_feet import add_covered_foot_lead, foot_rise
from evpose.tracker.event_registration import EventRegistration
from evpose.tracker.event_registration_config import EventRegistrationConfig

FX = 171.0
K = np.array([[FX, 0.0, 119.5], [0.0, FX, 89.5], [0.0, 0.0, 1.0]])
HEIGHT = 0.4
"""A box 0.4 m high from x = 0 to 0.6 m; its west face (normal -x) faces the camera at x = -3 m, 5 m up."""


def box_scene():
    ys = np.linspace(-0.3, 0.3, 7)
    rows = []  # (point, plane normal, edge normal, region)
    for y in ys:
        rows.append(((-0.01, y, 0.0), (0, 0, 1), (1, 0, 0), 0))  # ground beside the foot
        rows.append(((0.0, y, 0.01), (-1, 0, 0), (0, 0, -1), 1))  # the face's own foot
        rows.append(((0.0, y, HEIGHT - 0.01), (-1, 0, 0), (0, 0, 1), 1))  # the face's top
        rows.append(((0.01, y, HEIGHT), (0, 0, 1), (-1, 0, 0), 2))  # the box's top beside its rim
        rows.append(((-1.5, y, 0.0), (0, 0, 1), (1, 0, 0), 0))  # ground far from any face
    points = np.array([r[0] for r in rows], float)
    plane = np.array([r[1] for r in rows], float)
    edge = np.array([r[2] for r in rows], float)
    region = np.array([r[3] for r in rows])
    return points, plane, edge, region


def camera(x=-3.0, z=5.0):
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # looking down, image x along world x
    T[:3, 3] = (x, 0.0, z)
    return T


def test_feet_rise_to_their_face_top_and_nothing_else_does():
    points, plane, edge, region = box_scene()
    rise = foot_rise(points, plane, region, 0.02)
    kind = np.arange(len(points)) % 5
    # up to the face region's highest point (0.39 m): from the ground beside the foot (a crease partner) and the face's foot
    np.testing.assert_allclose(rise[kind == 0], HEIGHT - 0.01, atol=1e-9)
    np.testing.assert_allclose(rise[kind == 1], HEIGHT - 0.02, atol=1e-9)
    assert np.all(rise[kind >= 2] == 0)  # the face's top, the box's top and far ground
    assert np.all(foot_rise(points, None, region, 0.02) == 0)
    assert np.all(foot_rise(points, plane, region, 0.0) == 0)


def leads_for(points, plane, edge, region, twist, T, max_width=12.0, extra=0.1):
    rise = foot_rise(points, plane, region, 0.02)
    tangents = np.cross(plane, edge)
    off = np.full(len(points), -0.2)
    n = add_covered_foot_lead(off, np.arange(len(points)), points, tangents, rise, T, K, twist, max_width, extra)
    return off, n


def test_a_face_narrowing_towards_its_foot_moves_the_feet_off_lead_only():
    points, plane, edge, region = box_scene()
    kind = np.arange(len(points)) % 5
    towards = np.array([0, 0, 0, 2.0, 0, 0])  # flying +x, towards the box: the face's image lies behind its foot
    off, n = leads_for(points, plane, edge, region, towards, camera())
    feet = kind <= 1
    assert n == feet.sum()
    np.testing.assert_allclose(off[feet], -0.1)
    assert np.all(off[~feet] == -0.2)


def test_a_widening_face_a_wide_face_and_no_motion_leave_the_leads():
    points, plane, edge, region = box_scene()
    away = np.array([0, 0, 0, -2.0, 0, 0])  # flying away: the face lies ahead of its foot's image motion
    for twist, max_width in ((away, 12.0), (np.array([0, 0, 0, 2.0, 0, 0]), 5.0), (np.zeros(6), 12.0)):
        off, n = leads_for(points, plane, edge, region, twist, camera(), max_width)  # the face spans ~9 px here
        assert n == 0
        assert np.all(off == -0.2)


def test_the_event_registration_applies_it_only_when_set_and_only_with_a_twist():
    points, plane, edge, region = box_scene()
    tangents = np.cross(plane, edge)
    used = np.arange(len(points))
    twist = np.array([0, 0, 0, 2.0, 0, 0])
    base = EventRegistrationConfig()
    on0, off0 = EventRegistration(base, 240, 180, points, tangents, edge, None, plane, region)._leads(used, camera(), twist, K)
    cfg = dataclasses.replace(base, covered_foot_off_lead_px=0.1, covered_foot_max_width_px=100.0)
    reg = EventRegistration(cfg, 240, 180, points, tangents, edge, None, plane, region)
    on1, off1 = reg._leads(used, camera(), twist, K)
    kind = used % 5
    np.testing.assert_array_equal(on1, on0)
    np.testing.assert_allclose(off1[kind <= 1], off0[kind <= 1] + 0.1)
    np.testing.assert_array_equal(off1[kind > 1], off0[kind > 1])
    np.testing.assert_array_equal(reg._leads(used, camera())[1], off0)  # no twist: nothing to tell the side from
    ground_only = EventRegistration(dataclasses.replace(cfg, covered_foot_wall_side=False), 240, 180, points, tangents, edge, None,
                                    plane, region)
    off2 = ground_only._leads(used, camera(), twist, K)[1]
    np.testing.assert_allclose(off2[kind == 0], off0[kind == 0] + 0.1)
    np.testing.assert_array_equal(off2[kind != 0], off0[kind != 0])
