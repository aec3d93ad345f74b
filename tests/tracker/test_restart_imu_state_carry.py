"""Options of a carried restart after an event gap (no ground truth, ``full``), both off by default (session 28): turn
the carried pose by the gyroscope over the warm-up (``restart_gate.carry_rotation``), start the fusion from the biases
estimated before the gap (``restart_gate.carry_biases``); a session's start is unchanged either way."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.core.camera import CameraCalibration
from evpose.core.imu import ImuSamples
from evpose.core.stream_gaps import EventGap
from evpose.fusion import FusionMotionPredictor
from evpose.tracker.config import TrackerConfig
from evpose.tracker.event_gaps import carried_restart_pose, warmup_angular_velocity
from evpose.tracker.session import TrackingSession


def test_the_carried_pose_turns_at_the_given_rate_over_the_same_event_time():
    gap = EventGap(1_000_000, 3_000_000, "events")
    w = np.array([0.0, 0.0, 1.0])  # rad/s about the camera's z
    out = carried_restart_pose(np.eye(4), np.array([2.0, 0.0, 0.0]), gap, 1_002_000, 3_030_000, w)
    # 28 ms (the warm-up less the 2 ms the estimate is past the gap's last event), as the position.
    assert np.allclose(out[:3, 3], [0.056, 0.0, 0.0])
    assert np.allclose(out[:3, :3], Rotation.from_rotvec([0.0, 0.0, 0.028]).as_matrix())
    still = carried_restart_pose(np.eye(4), np.zeros(3), gap, 1_002_000, 3_030_000, None)
    assert np.array_equal(still, np.eye(4))


def test_the_warmup_rate_is_the_mean_gyro_after_the_gap_less_its_bias_in_the_camera_frame():
    R = Rotation.from_euler("z", 90, degrees=True).as_matrix()
    T = np.eye(4)
    T[:3, :3] = R
    cal = CameraCalibration(346, 260, 200.0, 200.0, 172.5, 129.5, T_cam_imu=T)
    t = np.arange(0, 4_000_000, 2000, dtype=np.int64)
    gyro = np.where((t >= 3_000_000)[:, None], [0.5, 0.0, 0.0], [9.0, 9.0, 9.0])  # only the warm-up's samples count
    imu = ImuSamples(t, np.zeros((len(t), 3)), gyro.astype(np.float64))
    gap = EventGap(1_000_000, 3_000_000, "events")
    w = warmup_angular_velocity(imu, gap, 3_030_000, cal, np.array([0.1, 0.0, 0.0]))
    assert np.allclose(w, R @ [0.4, 0.0, 0.0])
    assert warmup_angular_velocity(imu[:0], gap, 3_030_000, cal, None) is None
    assert warmup_angular_velocity(None, gap, 3_030_000, cal, None) is None


def _session(rec, cmap, **gate):
    cfg = TrackerConfig()
    cfg.restart_gate = dataclasses.replace(cfg.restart_gate, min_chance_z=0.0, **gate)
    t0 = max(int(rec.ground_truth.t[0]), int(rec.events.t[0]) + int(round(cfg.warmup_ms * 1e3)))
    return TrackingSession(rec, cmap, cfg, initial_pose=rec.ground_truth.interpolate(t0).matrix(0), t_start_us=t0)


def _to_the_restart(session):
    """Step to the update standing for the gap; returns (the fused state before it, the one the restart started
    from)."""
    before = None
    while (r := session.step()) is not None:
        if "the track is lost over the gap" in r.reason:
            return before, session.tracker.components.motion.last
        before = session.tracker.components.motion.last.copy()
    raise AssertionError("no gap")


def test_the_restarted_fusion_starts_from_the_biases_estimated_before_the_gap(paused_landing):
    rec, cmap = paused_landing
    before, start = _to_the_restart(_session(rec, cmap, carry_biases=True))
    assert np.linalg.norm(before.acc_bias) > 0 and np.linalg.norm(before.gyro_bias) > 0
    assert np.array_equal(start.acc_bias, before.acc_bias) and np.array_equal(start.gyro_bias, before.gyro_bias)
    _, zero = _to_the_restart(_session(rec, cmap))  # the default: from zero, as at a session's start
    assert not zero.acc_bias.any() and not zero.gyro_bias.any()


def test_the_carried_restart_is_turned_by_the_warmup_gyro(paused_landing):
    rec, cmap = paused_landing
    res = _session(rec, cmap, carry_rotation=True).run()
    g = next(k for k, r in enumerate(res) if "the track is lost over the gap" in r.reason)
    flat = _session(rec, cmap).run()  # the default: not turned
    # The same position, turned by the gyroscope's rate over the warm-up (the small landing turns slowly: < 1 deg).
    assert np.array_equal(res[g].pose[:3, 3], flat[g].pose[:3, 3])
    turn = Rotation.from_matrix(flat[g].pose[:3, :3].T @ res[g].pose[:3, :3]).magnitude()
    assert 0 < turn < np.radians(1.0)
    assert all(np.array_equal(p.pose, q.pose) for p, q in zip(res[:g], flat[:g]))  # nothing before the gap changes


def test_a_start_without_initial_biases_initialises_the_backend_as_before():
    calls = []

    class Backend:
        def initialize(self, *args, **kwargs):
            calls.append((args, kwargs))

    m = FusionMotionPredictor(Backend(), None, np.ones(3))
    m.reset(5, np.eye(4))
    assert calls[-1][1] == {}  # the call as it was: biases zero by the backend's default
    m.initial_biases = (np.full(3, 0.1), np.full(3, 0.01))
    m.reset(6, np.eye(4))
    assert np.array_equal(calls[-1][1]["acc_bias"], np.full(3, 0.1))
    assert np.array_equal(calls[-1][1]["gyro_bias"], np.full(3, 0.01))
