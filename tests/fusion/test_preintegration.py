"""IMU buffering and preintegration against gtsam's own integration and the analytic ground truth."""

import gtsam
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.core.imu import ImuSamples
from evpose.errors import InputError
from evpose.fusion.config import FusionConfig
from evpose.fusion.preintegration import ImuBuffer, make_preintegration_params, preintegrate

from fusion_helpers import make_motion


def _nav(motion, t_us):
    T = motion.pose_imu(t_us)[0]
    return gtsam.NavState(gtsam.Pose3(T), motion.velocity(np.array([t_us]))[0])


def test_preintegration_between_two_states_matches_ground_truth():
    m = make_motion(duration_s=1.0, imu_rate_hz=1000.0)
    buf = ImuBuffer()
    buf.add(m.imu())
    params = make_preintegration_params(FusionConfig())
    t0, t1 = m.config.t0_us + 100_300, m.config.t0_us + 600_700  # off the sample grid on purpose
    pim = preintegrate(buf, params, gtsam.imuBias.ConstantBias(), t0, t1)
    pred = pim.predict(_nav(m, t0), gtsam.imuBias.ConstantBias())
    T_gt = m.pose_imu(t1)[0]
    assert np.linalg.norm(pred.pose().translation() - T_gt[:3, 3]) < 2e-4
    R_err = pred.pose().rotation().matrix().T @ T_gt[:3, :3]
    assert np.degrees(np.arccos(np.clip((np.trace(R_err) - 1) / 2, -1, 1))) < 0.01
    assert np.linalg.norm(pred.velocity() - m.velocity(np.array([t1]))[0]) < 1e-3
    assert pim.deltaTij() == pytest.approx(0.5004)


def test_preintegration_matches_gtsam_fed_sample_by_sample():
    m = make_motion(duration_s=0.5, imu_rate_hz=500.0, acc_bias=(0.1, 0.0, -0.1), gyro_bias=(0.01, 0.02, 0.0))
    imu = m.imu()
    buf = ImuBuffer()
    buf.add(imu)
    params = make_preintegration_params(FusionConfig())
    bias = gtsam.imuBias.ConstantBias(np.array([0.1, 0.0, -0.1]), np.array([0.01, 0.02, 0.0]))
    t0, t1 = int(imu.t[10]), int(imu.t[200])
    ours = preintegrate(buf, params, bias, t0, t1)
    ref = gtsam.PreintegratedCombinedMeasurements(params, bias)
    ba, bg = np.array([0.1, 0.0, -0.1]), np.array([0.01, 0.02, 0.0])
    for k in range(10, 200):
        # gtsam's own scheme, fed the interval average of the two bounding samples (force rotated to mid-interval).
        a = 0.5 * (imu.acc[k] + imu.acc[k + 1])
        w = 0.5 * (imu.gyro[k] + imu.gyro[k + 1])
        dt = (imu.t[k + 1] - imu.t[k]) * 1e-6
        a = ba + Rotation.from_rotvec((w - bg) * dt / 2).apply(a - ba)
        ref.integrateMeasurement(a, w, dt)
    nav = _nav(m, t0)
    p1, p2 = ours.predict(nav, bias), ref.predict(nav, bias)
    assert np.allclose(p1.pose().translation(), p2.pose().translation(), atol=1e-12)
    assert np.allclose(p1.velocity(), p2.velocity(), atol=1e-12)
    assert np.allclose(ours.preintMeasCov(), ref.preintMeasCov(), rtol=1e-9, atol=1e-15)
    # And a combined IMU factor between the true states has (nearly) zero error.
    f = gtsam.CombinedImuFactor(1, 2, 3, 4, 5, 6, ours)
    v = gtsam.Values()
    T1 = m.pose_imu(t1)[0]
    v.insert(1, nav.pose())
    v.insert(2, nav.velocity())
    v.insert(3, gtsam.Pose3(T1))
    v.insert(4, m.velocity(np.array([t1]))[0])
    v.insert(5, bias)
    v.insert(6, bias)
    assert np.linalg.norm(f.unwhitenedError(v)[:9]) < 2e-4


def test_buffer_applies_time_offset_and_ignores_overlap():
    buf = ImuBuffer(time_offset_us=500)
    t = np.arange(0, 10_000, 1000, dtype=np.int64)
    imu = ImuSamples.from_arrays(t, np.ones((10, 3)), np.zeros((10, 3)))
    buf.add(imu[:6])
    buf.add(imu[3:])  # overlapping chunk
    assert len(buf) == 10
    assert buf.samples.t[0] == -500 and np.all(np.diff(buf.samples.t) == 1000)


def test_buffer_rejects_nan_and_unsorted_samples_with_input_error():
    buf = ImuBuffer()
    acc = np.zeros((3, 3))
    acc[1, 2] = np.nan
    with pytest.raises(InputError, match="IMU sample 1"):
        buf.add(ImuSamples.from_arrays([0, 1, 2], acc, np.zeros((3, 3))))
    with pytest.raises(InputError, match="does not increase"):
        buf.add(ImuSamples.from_arrays([0, 5, 5], np.zeros((3, 3)), np.zeros((3, 3))))


def test_pieces_over_a_long_buffer_equal_interpolation_over_all_samples():
    rng = np.random.default_rng(5)
    t = np.cumsum(rng.integers(1500, 2500, 400)).astype(np.int64)
    buf = ImuBuffer()
    buf.add(ImuSamples.from_arrays(t, rng.normal(size=(400, 3)), rng.normal(size=(400, 3))))
    s = buf.samples
    for t0, t1 in [(int(t[10]) + 7, int(t[12]) - 3), (int(t[0]) - 900, int(t[3])), (int(t[-3]), int(t[-1]) + 800), (int(t[100]), int(t[101]))]:
        dts, acc, gyro = buf.pieces(t0, t1)
        bounds = np.concatenate([[t0], s.t[(s.t > t0) & (s.t < t1)], [t1]]).astype(np.float64)
        mids = 0.5 * (bounds[:-1] + bounds[1:])
        ts = s.t.astype(np.float64)
        assert np.array_equal(acc, np.stack([np.interp(mids, ts, s.acc[:, k]) for k in range(3)], axis=1))
        assert np.array_equal(gyro, np.stack([np.interp(mids, ts, s.gyro[:, k]) for k in range(3)], axis=1))
        assert np.array_equal(dts, np.diff(bounds) * 1e-6)


def test_buffer_version_changes_with_its_samples():
    buf = ImuBuffer()
    v0 = buf.version
    t = np.arange(0, 10_000, 1000, dtype=np.int64)
    imu = ImuSamples.from_arrays(t, np.ones((10, 3)), np.zeros((10, 3)))
    buf.add(imu[:5])
    v1 = buf.version
    buf.add(imu[:5])  # nothing new
    assert buf.version == v1 != v0
    buf.set_samples(imu)
    assert buf.version != v1 and ImuBuffer().version not in (v0, v1, buf.version)


def test_buffer_appends_in_place_without_changing_samples_handed_out_or_adopted():
    rng = np.random.default_rng(7)
    t = np.cumsum(rng.integers(900, 1100, 300)).astype(np.int64)
    imu = ImuSamples.from_arrays(t, rng.normal(size=(300, 3)), rng.normal(size=(300, 3)))
    whole = ImuBuffer()
    whole.add(imu)
    buf = ImuBuffer()
    views = []
    for i in range(0, 300, 3):
        buf.add(imu[max(i - 1, 0) : i + 3])  # overlapping chunks: the repeated sample is ignored
        views.append((len(buf.samples), buf.samples, buf.samples.acc.copy()))
    assert np.array_equal(buf.samples.t, whole.samples.t) and np.array_equal(buf.samples.acc, whole.samples.acc)
    assert all(len(v) == n and np.array_equal(v.acc, acc) for n, v, acc in views)  # later appends never wrote into them
    adopted = views[10][1]  # the first 33 samples
    before = adopted.acc.copy()
    other = ImuBuffer()
    other.set_samples(adopted)
    other.add(imu[30:60])
    assert np.array_equal(adopted.acc, before) and len(adopted) == 33
    assert np.array_equal(other.samples.t, imu.t[:60]) and np.array_equal(other.samples.gyro, imu.gyro[:60])


def test_pieces_of_a_single_sample_buffer_hold_it():
    buf = ImuBuffer()
    buf.add(ImuSamples.from_arrays(np.array([5000]), [[1.0, 2.0, 3.0]], [[0.1, 0.2, 0.3]]))
    dts, acc, gyro = buf.pieces(1000, 9000)
    assert np.array_equal(dts, [0.004, 0.004]) and np.array_equal(acc, [[1.0, 2.0, 3.0]] * 2) and np.array_equal(gyro, [[0.1, 0.2, 0.3]] * 2)


def test_measurement_at_an_integer_time_is_kept_read_only_until_the_samples_change():
    buf = ImuBuffer()
    t = np.arange(0, 10_000, 2000, dtype=np.int64)
    buf.add(ImuSamples.from_arrays(t, np.arange(15.0).reshape(5, 3), -np.arange(15.0).reshape(5, 3)))
    acc, gyro = buf.measurement_at(3000)
    assert np.array_equal(acc, [4.5, 5.5, 6.5]) and not acc.flags.writeable and not gyro.flags.writeable
    assert buf.measurement_at(3000)[0] is acc
    buf.add(ImuSamples.from_arrays(np.array([10_000]), np.zeros((1, 3)), np.zeros((1, 3))))
    again, _ = buf.measurement_at(3000)
    assert again is not acc and np.array_equal(again, acc)
