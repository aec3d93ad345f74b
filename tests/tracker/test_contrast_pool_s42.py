"""Pooled passage counts (``ContrastLeadConfig.pool_radius_m``): a point reads the summed counts of its parallel
neighbours, so points that each see only a few events of a low-contrast edge are still trusted."""

import numpy as np

from evpose.tracker.contrast_leads import ContrastLeadConfig, PassageCounts, pool_neighbours


def _line_and_cross():
    # Five points 1 cm apart along x, one point 1 cm off them with a tangent along y, one without a tangent.
    pts = np.array([[0.00, 0, 0], [0.01, 0, 0], [0.02, 0, 0], [0.03, 0, 0], [0.04, 0, 0], [0.02, 0.01, 0], [0.02, -0.01, 0]])
    tg = np.array([[1.0, 0, 0]] * 5 + [[0, 1.0, 0], [0, 0, 0]])
    return pts, tg


def test_neighbours_are_the_parallel_points_within_the_radius_and_the_point_itself():
    pts, tg = _line_and_cross()
    indptr, idx = pool_neighbours(pts, tg, 0.015, 0.9)
    rows = [list(idx[indptr[i]:indptr[i + 1]]) for i in range(len(pts))]
    assert rows[0] == [0, 1] and rows[2] == [1, 2, 3] and rows[4] == [3, 4]
    assert rows[5] == [5]  # across the line: not parallel
    assert rows[6] == []  # no tangent: takes no events, pools nothing
    empty = pool_neighbours(pts, tg, 0.0, 0.9)
    assert empty[0].size == 0 and empty[1].size == 0


def test_pooled_counts_trust_points_whose_own_counts_are_too_few():
    pts, tg = _line_and_cross()
    on_own, on_pool = np.zeros(5), np.zeros(5)
    for radius, on in ((0.0, on_own), (0.05, on_pool)):
        counts = PassageCounts(ContrastLeadConfig(lone_on_lead_px=-0.2, min_events=10.0, pool_radius_m=radius), len(pts), pts, tg)
        counts.events[:5], counts.starts[:5] = 3.0, 3.0  # each point: 3 events, one per passage
        counts.events[5], counts.starts[5] = 3.0, 1.0  # the crossing edge fires 3 per passage
        counts.add_leads(np.arange(5), on, np.zeros(5))
    assert not on_own.any()  # 3 events each: below min_events alone
    assert np.allclose(on_pool, -0.2)  # 15 pooled events at one per passage
    mixed = PassageCounts(ContrastLeadConfig(lone_on_lead_px=-0.2, min_events=10.0, pool_radius_m=0.05), len(pts), pts, tg)
    mixed.events[:5], mixed.starts[:5] = 6.0, 3.0  # two per passage: not lone, pooled or not
    on = np.zeros(5)
    mixed.add_leads(np.arange(5), on, np.zeros(5))
    assert not on.any()
