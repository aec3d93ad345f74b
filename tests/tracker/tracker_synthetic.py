"""A small generative scene for tracker tests: box edges seen by a down-looking camera on a smooth path.

Events are generated, not stored: dense samples along the true 3D edges are
projected along a known trajectory, and an event fires whenever a sample's
pixel changes (the edge crossed a pixel), plus uniform background noise. The
contour map is a sparser sampling of the same edges.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.camera import CameraCalibration
from evpose.core.contour_map import ContourMap
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory

BOXES = [  # (centre x, centre y, half x, half y, height)
    (-0.35, -0.25, 0.18, 0.12, 0.25),
    (0.30, -0.20, 0.15, 0.20, 0.40),
    (-0.25, 0.30, 0.20, 0.15, 0.15),
    (0.35, 0.35, 0.12, 0.12, 0.30),
    (0.0, 0.0, 0.10, 0.25, 0.10),
]


def box_edges() -> np.ndarray:
    """(E, 2, 3) segments: top and bottom rectangles and vertical edges of every box."""
    segs = []
    for cx, cy, hx, hy, h in BOXES:
        corners = np.array([[cx - hx, cy - hy], [cx + hx, cy - hy], [cx + hx, cy + hy], [cx - hx, cy + hy]])
        for z in (0.0, h):
            for i in range(4):
                a, b = corners[i], corners[(i + 1) % 4]
                segs.append([[a[0], a[1], z], [b[0], b[1], z]])
        for c in corners:
            segs.append([[c[0], c[1], 0.0], [c[0], c[1], h]])
    return np.asarray(segs, dtype=np.float64)


def sample_edges(edges: np.ndarray, spacing_m: float) -> np.ndarray:
    pts = []
    for a, b in edges:
        n = max(int(np.ceil(np.linalg.norm(b - a) / spacing_m)), 1)
        s = (np.arange(n) + 0.5) / n
        pts.append(a + s[:, None] * (b - a))
    return np.concatenate(pts)


def calibration(width: int = 240, height: int = 180) -> CameraCalibration:
    f = 0.83 * width
    return CameraCalibration(width, height, f, f, (width - 1) / 2, (height - 1) / 2)


def trajectory(duration_s: float, rate_hz: float = 2000.0) -> Trajectory:
    """Down-looking camera 1.6 m above ground, drifting and wobbling (smooth, ~0.2 m/s, ~20 deg/s)."""
    t = np.arange(0.0, duration_s + 1e-9, 1.0 / rate_hz)
    pos = np.stack([0.15 * np.sin(1.3 * t), 0.1 * np.sin(0.9 * t + 0.4), 1.6 - 0.2 * t], axis=1)
    base = Rotation.from_matrix(np.diag([1.0, -1.0, -1.0]))
    wob = Rotation.from_rotvec(np.stack([0.08 * np.sin(2.0 * t), 0.06 * np.sin(1.7 * t + 1.0), 0.1 * np.sin(1.1 * t)], axis=1))
    rot = wob * base
    return Trajectory.from_arrays((t * 1e6).astype(np.int64), pos, rot.as_quat())


def generate(duration_s: float = 0.4, width: int = 240, height: int = 180, noise_rate_hz: float = 2e4, seed: int = 0, spacing_m: float = 0.0015):
    """(Recording, ContourMap, signal_mask): events with ground truth, the map, and which events are signal."""
    rng = np.random.default_rng(seed)
    cal = calibration(width, height)
    edges = box_edges()
    dense = sample_edges(edges, spacing_m)
    gt = trajectory(duration_s)
    # Fixed per-sample polarity (which side is brighter); the combined-polarity tracker does not care.
    pol = np.where(rng.random(dense.shape[0]) < 0.5, 1, -1).astype(np.int8)
    T = gt.matrices()
    prev = None
    ts, xs, ys, ps = [], [], [], []
    for k in range(len(gt)):
        R, c = T[k, :3, :3], T[k, :3, 3]
        Xc = (dense - c) @ R
        z = Xc[:, 2]
        uv = cal.K[:2, :2] @ (Xc[:, :2] / z[:, None]).T + cal.K[:2, 2:3]
        px = np.rint(uv.T).astype(np.int64)
        inside = (z > 0.05) & (px[:, 0] >= 0) & (px[:, 0] < width) & (px[:, 1] >= 0) & (px[:, 1] < height)
        code = np.where(inside, px[:, 1] * width + px[:, 0], -1)
        if prev is not None:
            fire = (code != prev) & (code >= 0)
            idx = np.flatnonzero(fire)
            if idx.size:
                _, first = np.unique(code[idx], return_index=True)
                idx = idx[np.sort(first)]
                jitter = rng.integers(0, int(gt.t[1] - gt.t[0]), idx.size)
                ts.append(gt.t[k - 1] + jitter)
                xs.append(px[idx, 0])
                ys.append(px[idx, 1])
                ps.append(pol[idx])
        prev = code
    t = np.concatenate(ts)
    x = np.concatenate(xs)
    y = np.concatenate(ys)
    p = np.concatenate(ps)
    n_noise = rng.poisson(noise_rate_hz * duration_s)
    t = np.concatenate([t, rng.integers(0, int(gt.t[-1]), n_noise)])
    x = np.concatenate([x, rng.integers(0, width, n_noise)])
    y = np.concatenate([y, rng.integers(0, height, n_noise)])
    p = np.concatenate([p, np.where(rng.random(n_noise) < 0.5, 1, -1)])
    signal = np.concatenate([np.ones(t.size - n_noise, bool), np.zeros(n_noise, bool)])
    order = np.argsort(t, kind="stable")
    events = EventArray.from_arrays(t[order], x[order], y[order], p[order].astype(np.int8))
    cmap = ContourMap.from_points(sample_edges(edges, 0.01))
    rec = Recording(events=events, ground_truth=gt, calibration=cal, metadata={"generator": "tests/tracker/tracker_synthetic.py"})
    return rec, cmap, signal[order]


def step_windows(tracker, events: EventArray, t0_us: int, n: int, window_us: int = 5_000) -> list:
    """``n`` tracker steps of ``window_us`` each from ``t0_us``, fed the events of each window; their results."""
    out = []
    for _ in range(n):
        out.append(tracker.step(t0_us + window_us, events.time_window(t0_us, t0_us + window_us)))
        t0_us += window_us
    return out


def assert_restore_replays_bit_identically(started, events: EventArray, n_before: int = 7, n_detour: int = 4, n_after: int = 7) -> list:
    """A straight run of ``started()`` against one that snapshots after ``n_before`` steps, runs ``n_detour`` more,
    restores and replays: the replayed steps give the same poses and counts. Returns the straight run's results."""
    w = 5_000
    straight = step_windows(started(), events, 0, n_before + n_after)
    tr = started()
    step_windows(tr, events, 0, n_before)
    snap = tr.snapshot()
    step_windows(tr, events, n_before * w, n_detour)
    tr.restore(snap)
    replay = step_windows(tr, events, n_before * w, n_after)
    for x, y in zip(straight[n_before:], replay):
        assert np.array_equal(x.pose, y.pose) and x.counts == y.counts
    return straight


def run_full(rec: Recording, cmap: ContourMap, **fusion) -> "TrackingSession":
    """A ``full``-mode session over all of ``rec`` with the given ``FusionConfig`` fields set."""
    from evpose.tracker.config import TrackerConfig, TrackerMode
    from evpose.tracker.session import TrackingSession

    cfg = TrackerConfig(mode=TrackerMode.FULL)
    for name, value in fusion.items():
        setattr(cfg.fusion, name, value)
    s = TrackingSession(rec, cmap, cfg)
    s.run()
    return s
