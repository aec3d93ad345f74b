"""Tests of the scene-richness figure of evpose/bench/slam.py (kept with the SLAM tests, whose area owns the module)."""

import cv2
import numpy as np

from evpose.bench.slam import strong_corner_count


def _blurred(draw) -> np.ndarray:
    img = np.zeros((100, 120), np.float32)
    draw(img)
    return cv2.GaussianBlur(img, (5, 5), 1.0)


def test_strong_corners_count_box_corners_but_not_points_along_a_straight_edge():
    box = _blurred(lambda im: cv2.rectangle(im, (30, 30), (80, 70), 5.0, 2))
    line = _blurred(lambda im: cv2.line(im, (5, 50), (115, 50), 5.0, 1))
    assert strong_corner_count(box) >= 4  # inner and outer corners of the outline
    assert strong_corner_count(line) <= 2  # only the two ends: the rest of the edge is ambiguous along itself
    assert strong_corner_count(np.zeros((20, 20), np.float32)) == 0


def test_inertial_spread_counts_seeds_within_both_targets_and_the_ones_never_made_metric():
    from evpose.bench.slam import inertial_spread_summary

    runs = [(0, 0.005, 0.002, True), (3, 0.012, 0.015, False), (6, 0.005, 0.009, False), (7, 0.98, 0.002, False), (9, np.nan, 0.001, True)]
    s = inertial_spread_summary(runs)
    assert s["within_targets"] == 2  # seeds 0 and 6; a NaN RPE never counts as within
    assert s["never_metric"] == 3
    assert s["rpe_rot_deg_per_m_worst"] == 0.015
    assert np.isnan(s["rpe_trans_per_m_worst"])  # a NaN run must show in the worst figure, not hide behind the others
    assert "s7 0.9800 m/m" in s["per_seed"] and "(not metric)" in s["per_seed"]
