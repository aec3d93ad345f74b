"""Shared set-up of the tracker tests."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from evpose.core.contour_map import ContourMap
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.trajectory import Trajectory


@pytest.fixture(scope="module")
def landing_head(sim_landing_small):
    """``landing_head(seconds)``: the first ``seconds`` of the small simulated landing and a map sampled along its true
    edges every 2 cm."""

    def head(seconds: float):
        res = sim_landing_small
        rec = res.recording
        pts = []
        for a, b in res.edges:
            n = max(int(np.linalg.norm(b - a) / 0.02), 1)
            pts.append(a + (b - a) * (np.arange(n) / n)[:, None])
        t0 = int(rec.events.t[0])
        short = dataclasses.replace(rec, events=rec.events.time_window(t0, t0 + int(seconds * 1e6)))
        return short, ContourMap.from_points(np.concatenate(pts))

    return head


@pytest.fixture(scope="module")
def paused_landing(landing_head):
    """The first 0.3 s of the small landing with everything from 0.15 s on (events, IMU, ground truth) 2 s later: a
    recorder pause; and its map."""
    rec, cmap = landing_head(0.3)
    at, pause = int(rec.events.t[0]) + 150_000, 2_000_000
    off = rec.calibration.time_offset_us

    def later(t, at):
        return np.where(t >= at, t + pause, t)

    ev, gt, imu = rec.events, rec.ground_truth, rec.imu
    return dataclasses.replace(rec, events=EventArray(later(ev.t, at), ev.x, ev.y, ev.p),
                               ground_truth=Trajectory(later(gt.t, at), gt.position, gt.quat_xyzw),
                               imu=ImuSamples(later(imu.t, at + off), imu.acc, imu.gyro)), cmap
