"""``full`` started without the initial velocity holds the polarity filter (both polarities, no T_align) for its first updates."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.session import TrackingSession

HOLD = 8


@pytest.fixture(scope="module")
def landing(landing_head):
    """The first 0.15 s of the small simulated landing and a map sampled along its true edges (2 cm)."""
    return landing_head(0.15)


def _aligned(results) -> list[bool]:
    """Per update: did registration read a composed T_align (its counts carry the filter's event counts)?"""
    return ["events_polarity_judged" in r.counts for r in results]


def _session(rec, cmap, given_pose: bool, **cfg):
    config = TrackerConfig(mode=TrackerMode.FULL, **cfg)
    config.polarity.unknown_velocity_hold_updates = HOLD
    if not given_pose:
        return TrackingSession(rec, cmap, config)
    t0 = max(int(rec.ground_truth.t[0]), int(rec.events.t[0]) + int(round(config.warmup_ms * 1e3)))
    return TrackingSession(rec, cmap, config, initial_pose=rec.ground_truth.interpolate(t0).matrix(0), t_start_us=t0)


def test_a_start_without_velocity_registers_without_t_align_first(landing):
    rec, cmap = landing
    s = _session(rec, cmap, given_pose=True)
    s.run()
    assert _aligned(s.results)[:HOLD] == [False] * HOLD
    assert all(_aligned(s.results)[HOLD:])
    # Started from ground truth (the velocity given too) the filter runs from the first update.
    g = _session(rec, cmap, given_pose=False)
    g.run()
    assert all(_aligned(g.results))


def test_seeking_back_into_the_hold_replays_bit_identically(landing):
    rec, cmap = landing
    s = _session(rec, cmap, given_pose=True, snapshot_every=3)
    ref = [x.pose.copy() for x in s.run()]
    r = s.seek(s.results[4].t_us)
    assert np.array_equal(r.pose, ref[4])
    s.run()
    assert all(np.array_equal(a.pose, b) for a, b in zip(s.results, ref))
    assert _aligned(s.results)[:HOLD] == [False] * HOLD
