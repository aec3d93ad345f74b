"""find_gaps and merge_gaps: stretches of a sensor stream without samples."""

import numpy as np

from evpose.core.stream_gaps import EventGap, find_gaps, merge_gaps


def test_find_gaps_reports_only_gaps_longer_than_the_limit_ending_after_the_start():
    t = np.array([0, 5, 2_000, 2_001, 9_000, 9_100], dtype=np.int64)
    assert find_gaps(t, 1_000, after_us=0) == [EventGap(5, 2_000), EventGap(2_001, 9_000)]
    assert find_gaps(t, 1_000, after_us=3_000) == [EventGap(2_001, 9_000)]


def test_overlapping_gaps_of_the_events_and_the_imu_are_joined():
    gaps = merge_gaps([EventGap(100, 5_000, "IMU samples"), EventGap(90, 4_000), EventGap(9_000, 12_000, "IMU samples")])
    assert gaps == [EventGap(90, 5_000, "events or IMU samples"), EventGap(9_000, 12_000, "IMU samples")]
