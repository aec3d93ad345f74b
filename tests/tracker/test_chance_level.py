"""The chance level of an inlier share: how often points displaced a few pixels still land on recent events."""

import numpy as np

from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.tracker.chance_level import chance_counts


def _field(value: np.ndarray) -> TemporalDistanceField:
    h, w = value.shape
    f = TemporalDistanceField(DistanceFieldConfig(), w, h)
    f.value[0] = value
    f.box[:] = (0, h, 0, w)
    f.slots_ready = (0,)
    return f


def test_points_on_a_thin_edge_reach_chance_only_along_it():
    img = np.ones((60, 80), np.float32)
    img[30, :] = 0.0  # one recent horizontal edge
    uv = np.c_[np.arange(20.0, 60.0), np.full(40, 30.0)]
    c = chance_counts(_field(img), uv, None, 0.7)
    # Of the eight displacements only the two along the edge stay on it.
    assert c["chance_samples"] == 8 * 40 and c["chance_hits"] == 2 * 40


def test_events_everywhere_put_every_displaced_point_on_one():
    c = chance_counts(_field(np.zeros((60, 80), np.float32)), np.array([[40.0, 30.0], [20.0, 25.0]]), None, 0.7)
    assert c == {"chance_hits": 16, "chance_samples": 16}


def test_points_behind_the_camera_or_outside_the_field_are_not_sampled():
    c = chance_counts(_field(np.zeros((60, 80), np.float32)), np.array([[np.nan, np.nan], [-5.0, 30.0], [200.0, 1.0]]), None, 0.7)
    assert c == {"chance_hits": 0, "chance_samples": 0}
