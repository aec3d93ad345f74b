"""The viewer's seeking restores the coasting state that crosses steps (session 38: the held coast velocity and the
speed-jump refusal count were missing from :meth:`EventSlam.snapshot`)."""

import numpy as np

from evpose.slam.config import SlamConfig, SlamMode
from evpose.slam.system import EventSlam
from slam_synthetic import make_recording


def test_restore_brings_back_the_held_coast_velocity_and_the_refusal_count():
    rec = make_recording(duration_s=0.3, speed=1.5, seed=3)
    slam = EventSlam(SlamConfig(mode=SlamMode.EVENT_INERTIAL), rec.calibration, rec.imu)
    slam._coast_hold, slam._speed_refusals = (4, 123456, np.array([1.0, 2.0, 3.0])), 2
    snap = slam.snapshot()
    slam._coast_hold, slam._speed_refusals = None, 0
    slam.restore(snap)
    assert slam._coast_hold[:2] == (4, 123456)
    assert np.array_equal(slam._coast_hold[2], [1.0, 2.0, 3.0])
    assert slam._speed_refusals == 2
    # The snapshot is a copy: changing the restored state leaves the snapshot as it was.
    slam._coast_hold[2][0] = 9.0
    slam.restore(snap)
    assert slam._coast_hold[2][0] == 1.0
