"""``full`` with the fusion's revision read-out (``FusionConfig.revision_readout_states``): only the written poses
change; the registrations, and so the tracking itself, stay bit for bit as without it."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.session import TrackingSession
from tracker_synthetic import run_full


@pytest.fixture(scope="module")
def landing(landing_head):
    return landing_head(0.15)


def test_readout_changes_the_written_poses_only(landing):
    assert TrackerConfig().fusion.revision_readout_prior is False
    rec, cmap = landing
    off, on = run_full(rec, cmap, revision_readout_states=0), run_full(rec, cmap, revision_readout_states=7)
    assert len(off.results) == len(on.results) > 10
    for a, b in zip(off.results, on.results):
        assert a.t_us == b.t_us and a.status == b.status
        assert (a.registration_pose is None) == (b.registration_pose is None)
        if a.registration_pose is not None:
            assert np.array_equal(a.registration_pose, b.registration_pose)
    # The tracker's own pose (what a restart starts from) is the fused one either way.
    assert np.array_equal(off.tracker.pose, on.tracker.pose)
    moved = [np.linalg.norm(a.pose[:3, 3] - b.pose[:3, 3]) for a, b in zip(off.results, on.results)]
    assert max(moved[:6]) == 0.0 < moved[6]  # the 7th update is the first with 7 older states (state 0 the start)
    assert max(moved) > 0.0
    assert np.array_equal(on.trajectory().position, np.array([r.pose[:3, 3] for r in on.results]))


def test_readout_prior_closes_the_loop_through_the_tracker_pose(landing):
    rec, cmap = landing
    config = TrackerConfig(mode=TrackerMode.FULL)
    config.fusion.revision_readout_prior = True
    s = TrackingSession(rec, cmap, config)
    s.run()
    ref = run_full(rec, cmap, revision_readout_states=7)
    # The next registrations start from the moved prediction, so they differ; the tracker's pose is the written one.
    assert any(a.registration_pose is not None and b.registration_pose is not None
               and not np.array_equal(a.registration_pose, b.registration_pose) for a, b in zip(s.results, ref.results))
    assert np.array_equal(s.tracker.pose, s.results[-1].pose)
    assert not np.array_equal(ref.tracker.pose, ref.results[-1].pose)
