"""The fusion backends behind the tracker's MotionPredictor protocol."""

import numpy as np

from evpose.fusion import FusionConfig, make_fusion
from evpose.fusion.motion_predictor import FusionMotionPredictor

from fusion_helpers import WHITE, make_motion, pose_errors


def test_predictor_adapter_predicts_with_the_imu_and_marks_failures(calibration):
    m = make_motion(duration_s=0.5, imu_rate_hz=500.0)
    t0 = m.config.t0_us
    p = FusionMotionPredictor(make_fusion(FusionConfig(**WHITE), calibration), m.imu(), m.camera_velocity([t0], calibration.T_cam_imu)[0])
    times = t0 + np.arange(0, 400_000, 10_000)
    gt = m.camera_trajectory(times, calibration.T_cam_imu)
    p.reset(int(times[0]), gt.matrix(0))
    for k in range(1, len(times)):
        predicted = p.predict(int(times[k]))
        assert pose_errors(predicted, gt.matrix(k))[0] < 0.002
        if k == 20:
            assert p.report(int(times[k]), None, None).degraded
        else:
            p.update(int(times[k]), gt.matrix(k))
    snap = p.snapshot()
    a = p.predict(int(times[-1]) + 5000)
    p.update(int(times[-1]) + 10_000, gt.matrix(len(times) - 1))
    p.restore(snap)
    assert np.array_equal(p.predict(int(times[-1]) + 5000), a)
