"""Map-free event(-inertial) SLAM (second paper): adaptive event windows, MCIs, KLT tracking, two-view init, local BA, atlas.

Public API::

    from evpose.slam import SlamConfig, EventSlam, run_slam
    slam = EventSlam(SlamConfig(), calibration, imu=None)
    result = slam.step(events)      # SlamStepResult
    slam.atlas.maps                 # SlamMap: keyframes, points, trajectory()
    run = run_slam(recording, SlamConfig())
"""

from evpose.slam.config import SlamConfig, SlamMode
from evpose.slam.step_result import SlamStatus, SlamStepResult
from evpose.slam.system import EventSlam, SlamRun, run_slam

__all__ = ["EventSlam", "SlamConfig", "SlamMode", "SlamRun", "SlamStatus", "SlamStepResult", "run_slam"]
