"""The polarity rule checked on the project's simulator: painted pad boundaries on flat ground.

Painted edges are the clean case for the sign: both sides share one plane and
one shading, so the brightness sign is the albedo difference, read here from
the simulated cloud's intensity on either side of each edge.
"""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from evpose.fusion import PolarityPredictor, classify_events


@pytest.fixture(scope="module")
def landing():
    from evpose.sim import SimulationConfig, simulate

    return simulate(SimulationConfig(scenario="landing", seconds=0.12, resolution=(240, 180), seed=0, noise_free=True))


def _painted_edge_points(sim, spacing=0.01, probe=0.03):
    pts, nrm = [], []
    for a, b in sim.albedo_edges:
        length = np.linalg.norm(b - a)
        n = int(length / spacing)
        if n < 2:
            continue
        d = (b - a) / length
        normal = np.array([d[1], -d[0], 0.0]) / np.hypot(d[0], d[1])
        pts.append(a + ((np.arange(n) + 0.5) / n)[:, None] * (b - a))
        nrm.append(np.repeat(normal[None], n, 0))
    pts, nrm = np.concatenate(pts), np.concatenate(nrm)
    tree = cKDTree(sim.cloud_points)
    side = lambda off: np.median(sim.cloud_intensity[tree.query(pts + off * nrm, k=8)[1]], axis=1)  # noqa: E731
    return pts, nrm, np.sign(side(probe) - side(-probe)).astype(np.int8)


def test_polarity_prediction_agrees_with_simulated_events_outside_buffer(landing):
    rec, traj = landing.recording, landing.trajectory
    cal = rec.calibration
    K = cal.K
    pts, nrm, sign = _painted_edge_points(landing)
    assert np.count_nonzero(sign) > 100
    lever = np.linalg.inv(cal.T_cam_imu)[:3, 3]
    pred = PolarityPredictor()
    agree = judged = 0
    step = 3333
    for t1 in range(10_000, 120_000, step):
        ts = np.array([t1 * 1e-6])
        T = traj.camera_poses(ts)[0]
        wb = traj.body_rates(ts)[0]
        v = traj.body_velocity(ts)[0] + traj.body_rotation(ts).apply(np.cross(wb, lever))[0]
        pol = pred.predict(pts, nrm, sign, T, cal.T_cam_imu[:3, :3] @ wb, v, K)
        X = (pts - T[:3, 3]) @ T[:3, :3]
        uv = np.stack([K[0, 0] * X[:, 0] / X[:, 2] + K[0, 2], K[1, 1] * X[:, 1] / X[:, 2] + K[1, 2]], 1)
        ev = rec.events.time_window(t1 - step, t1)
        label, point = classify_events(ev.x, ev.y, ev.p, uv, pol, 2.0, cal.width, cal.height)
        j = (point >= 0) & (pol[np.maximum(point, 0)] != 0)
        agree += int(np.count_nonzero(j & (label == 1)))
        judged += int(np.count_nonzero(j))
    assert judged > 1000
    assert agree / judged >= 0.9, agree / judged
