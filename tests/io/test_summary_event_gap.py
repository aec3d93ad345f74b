"""summarize_recording's longest event gap: found within a batch and across two batches, with the event before it."""

import numpy as np

from evpose.io.summary import _longest_gap


def test_the_longest_gap_is_found_within_and_between_batches():
    best = _longest_gap(np.array([0, 10, 500, 510]), None, (0, 0))
    assert best == (490, 10)
    best = _longest_gap(np.array([2_000, 2_001]), 510, best)  # the gap lies between the two batches
    assert best == (1_490, 510)
    assert _longest_gap(np.array([], np.int64), 2_001, best) == best
    assert _longest_gap(np.array([2_100]), 2_001, best) == best
