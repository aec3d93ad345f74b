"""Small synthetic recordings shared by the io tests (a plain module, so test files can import it)."""

import numpy as np
from evpose.core.camera import CameraCalibration, DistortionModel
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory


def make_recording(n=20_000, seed=0, width=240, height=180, t0=1_000_000, duration_us=3_000_000, with_calibration=True):
    rng = np.random.default_rng(seed)
    t = np.sort(rng.integers(t0, t0 + duration_us, n))
    ev = EventArray.from_arrays(t, rng.integers(0, width, n), rng.integers(0, height, n), rng.integers(0, 2, n))
    ti = np.arange(t0, t0 + duration_us, 1000)
    imu = ImuSamples.from_arrays(ti, rng.normal(size=(ti.size, 3)), rng.normal(size=(ti.size, 3)))
    tg = ti[::5]
    q = rng.normal(size=(tg.size, 4))
    gt = Trajectory.from_arrays(tg, rng.normal(size=(tg.size, 3)), q)
    T = np.eye(4)
    T[:3, 3] = [0.01, 0.002, -0.03]
    cal = CameraCalibration(width, height, 199.1, 198.7, (width - 1) / 2, (height - 1) / 2, DistortionModel.RADTAN, (-0.33, 0.12, 0.0004, -0.0002, 0.0), T, 250) if with_calibration else None
    meta = {"scenario": "unit-test", "seed": seed} if with_calibration else {"width": width, "height": height}
    return Recording(ev, imu, gt, cal, meta)


def assert_same_recording(a: Recording, b: Recording, metadata=True, extrinsic=True):
    for c in "txyp":
        np.testing.assert_array_equal(getattr(a.events, c), getattr(b.events, c))
    for name in ("imu", "ground_truth"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None)
        if x is not None:
            np.testing.assert_array_equal(x.t, y.t)
    if a.imu is not None:
        np.testing.assert_array_equal(a.imu.acc, b.imu.acc)
        np.testing.assert_array_equal(a.imu.gyro, b.imu.gyro)
    if a.ground_truth is not None:
        np.testing.assert_allclose(a.ground_truth.position, b.ground_truth.position, rtol=0, atol=0)
        np.testing.assert_allclose(a.ground_truth.quat_xyzw, b.ground_truth.quat_xyzw, rtol=0, atol=1e-15)
    assert (a.calibration is None) == (b.calibration is None)
    if a.calibration is not None:
        da, db = a.calibration.to_dict(), b.calibration.to_dict()
        if not extrinsic:  # formats such as CameraInfo hold intrinsics only
            for key in ("T_cam_imu", "time_offset_us"):
                da.pop(key), db.pop(key)
        assert da == db
    if metadata:
        assert a.metadata == b.metadata


