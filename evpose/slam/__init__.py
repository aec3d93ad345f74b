"""Map-free event(-inertial) SLAM (second paper): adaptive event windows, MCIs, KLT tracking, two-view init, local BA, atlas.

Public API::

    from evpose.slam import SlamConfig, EventSlam, run_slam
    slam = EventSlam(SlamConfig(), calibration, imu=None)
    result = slam.step(events)      # SlamStepResult
    slam.atlas.maps                 # SlamMap: keyframes, points, trajectory()
    run = run_slam(recording, SlamConfig())

Event-inertial mode (``SlamConfig(mode=SlamMode.EVENT_INERTIAL)``) runs one of the paper's
configurations, ``config.inertial.configuration``: E-I-C1 (a new map when lost), E-I-C2
(continuous: IMU bridges over visual failures; the default) or E-I-C3 (C2 with fixed tiny windows).
"""

from evpose.slam.config import SlamConfig, SlamMode
from evpose.slam.inertial import InertialConfiguration
from evpose.slam.step_result import SlamFailure, SlamStatus, SlamStepResult
from evpose.slam.run import SlamRun, run_slam
from evpose.slam.system import EventSlam

__all__ = ["EventSlam", "InertialConfiguration", "SlamConfig", "SlamFailure", "SlamMode", "SlamRun", "SlamStatus", "SlamStepResult", "run_slam"]
