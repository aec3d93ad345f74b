"""The fused modes' marginal pose covariance is a report only: ``fusion.compute_covariance`` off gives the same poses
bit for bit, so ``evpose track`` (which writes poses only) turns it off and writes what a default session tracks."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.cli.main import run
from evpose.io.h5 import write_recording_h5
from evpose.io.map_ply import read_contour_map, write_contour_map
from evpose.io.open import open_recording
from evpose.io.tum import read_tum, write_tum
from tracker_synthetic import run_full


@pytest.fixture(scope="module")
def head(landing_head):
    return landing_head(0.25)


def test_the_fused_poses_do_not_depend_on_the_reported_covariance(head):
    rec, cmap = head
    on, off = run_full(rec, cmap, compute_covariance=True), run_full(rec, cmap, compute_covariance=False)
    assert len(on.results) == len(off.results) > 20
    for a, b in zip(on.results, off.results):
        assert np.array_equal(a.pose, b.pose) and a.status == b.status
        assert np.array_equal(a.registration_pose, b.registration_pose)
        assert b.covariance is None
    assert all(r.covariance is not None and r.covariance.shape == (6, 6) for r in on.results[5:])


def test_track_writes_the_default_sessions_poses(head, tmp_path):
    rec, cmap = head
    write_recording_h5(tmp_path / "rec.h5", rec)
    write_contour_map(tmp_path / "map.ply", cmap)
    assert run(["track", str(tmp_path / "rec.h5"), "--map", str(tmp_path / "map.ply"), "--out", str(tmp_path / "e.txt"),
                "--mode", "full", "--no-progress"]) == 0
    # The same inputs as the command reads them (the map's PLY round trip included), the default configuration.
    s = run_full(open_recording(tmp_path / "rec.h5"), read_contour_map(tmp_path / "map.ply"), compute_covariance=True)
    write_tum(tmp_path / "expected.txt", s.trajectory())
    assert len(read_tum(tmp_path / "e.txt")) > 20
    assert (tmp_path / "e.txt").read_bytes() == (tmp_path / "expected.txt").read_bytes()
