"""The shared ``sim_landing_small`` fixture (tests/conftest.py) is what its documentation promises."""

import numpy as np


def test_sim_landing_small_matches_its_documentation(sim_landing_small):
    from evpose.io.h5 import read_recording_h5
    from evpose.io.map_ply import read_point_cloud

    rec = sim_landing_small.recording
    assert rec.calibration.resolution == (240, 180)
    assert rec.metadata["scenario"] == "landing" and rec.metadata["seed"] == 0
    assert rec.ground_truth.t[-1] == 1_000_000 and np.median(np.diff(rec.ground_truth.t)) == 1000
    assert len(rec.events) > 50_000
    back = read_recording_h5(sim_landing_small.files["recording"])
    np.testing.assert_array_equal(back.events.t, rec.events.t)
    np.testing.assert_array_equal(back.imu.acc, rec.imu.acc)
    pts, _ = read_point_cloud(sim_landing_small.files["cloud"])
    assert pts.shape == sim_landing_small.cloud_points.shape
    with np.load(sim_landing_small.files["edges"]) as z:
        np.testing.assert_array_equal(z["segments"], sim_landing_small.edges)
