"""Small recordings the viewer tests build themselves (a bar sweeping across a tiny sensor)."""

from __future__ import annotations

import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory


def sweeping_bar_recording(duration_s: float = 1.0, width: int = 64, height: int = 48, seed: int = 0) -> Recording:
    """A bright bar moving right at 40 px/s: ON events on its leading edge, OFF on its trailing edge, plus noise."""
    rng = np.random.default_rng(seed)
    ts, xs, ys, ps = [], [], [], []
    n_rows_per_tick = height
    dt_us = 2_000
    for k in range(int(duration_s * 1e6 / dt_us)):
        t = k * dt_us
        lead = int(8 + 40 * t / 1e6) % width
        trail = (lead - 6) % width
        for col, pol in ((lead, 1), (trail, -1)):
            rows = rng.choice(height, size=n_rows_per_tick // 2, replace=False)
            ts.append(t + np.sort(rng.integers(0, dt_us, rows.size)))
            xs.append(np.full(rows.size, col))
            ys.append(rows)
            ps.append(np.full(rows.size, pol))
        nn = 4
        ts.append(t + np.sort(rng.integers(0, dt_us, nn)))
        xs.append(rng.integers(0, width, nn))
        ys.append(rng.integers(0, height, nn))
        ps.append(rng.choice([-1, 1], nn))
    t = np.concatenate(ts)
    order = np.argsort(t, kind="stable")
    events = EventArray.from_arrays(t[order], np.concatenate(xs)[order], np.concatenate(ys)[order], np.concatenate(ps)[order])
    gt_t = np.arange(0, int(duration_s * 1e6) + 1, 5_000)
    pos = np.stack([gt_t / 1e6 * 0.2, np.zeros_like(gt_t, float), np.full(gt_t.shape, -1.0)], axis=1)
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (gt_t.size, 1))
    imu_t = np.arange(0, int(duration_s * 1e6) + 1, 5_000)
    imu = ImuSamples.from_arrays(imu_t, np.tile([0, 0, 9.81], (imu_t.size, 1)), np.zeros((imu_t.size, 3)))
    calib = CameraCalibration(width=width, height=height, fx=50.0, fy=50.0, cx=width / 2, cy=height / 2)
    return Recording(events, imu, Trajectory.from_arrays(gt_t, pos, quat), calib, {"scenario": "sweeping_bar"})


def _square_edges() -> np.ndarray:
    """Edges of three flat rectangles and one raised one: (E, 2, 3) segments in a z-up world."""
    segs = []
    for cx, cy, hx, hy, z in ((-0.3, -0.2, 0.15, 0.1, 0.0), (0.3, -0.15, 0.12, 0.18, 0.0), (-0.2, 0.3, 0.18, 0.12, 0.0), (0.25, 0.3, 0.1, 0.1, 0.2)):
        c = np.array([[cx - hx, cy - hy], [cx + hx, cy - hy], [cx + hx, cy + hy], [cx - hx, cy + hy]])
        for i in range(4):
            segs.append([[*c[i], z], [*c[(i + 1) % 4], z]])
    return np.asarray(segs, float)


def _sample(edges: np.ndarray, spacing: float) -> np.ndarray:
    out = []
    for a, b in edges:
        n = max(int(np.ceil(np.linalg.norm(b - a) / spacing)), 1)
        out.append(a + ((np.arange(n) + 0.5) / n)[:, None] * (b - a))
    return np.concatenate(out)


def map_scene(duration_s: float = 0.5, width: int = 160, height: int = 120, seed: int = 0, speed: float = 4.0):
    """(Recording, ContourMap): a down-looking camera drifting over rectangles; an event fires when an edge sample changes pixel."""
    from scipy.spatial.transform import Rotation

    from evpose.core.contour_map import ContourMap

    rng = np.random.default_rng(seed)
    f = 0.83 * width
    cal = CameraCalibration(width, height, f, f, (width - 1) / 2, (height - 1) / 2)
    t_s = np.arange(0.0, duration_s + 1e-9, 1 / 2000)
    u = speed * t_s  # fast enough that edges cross a pixel every few milliseconds
    pos = np.stack([0.15 * np.sin(1.3 * u), 0.1 * np.sin(0.9 * u), 1.5 - 0.2 * u / speed], axis=1)
    rot = Rotation.from_rotvec(np.stack([0.06 * np.sin(2 * u), 0.05 * np.sin(1.7 * u), 0.08 * np.sin(1.1 * u)], 1)) * Rotation.from_matrix(np.diag([1.0, -1, -1]))
    gt = Trajectory.from_arrays((t_s * 1e6).astype(np.int64), pos, rot.as_quat())
    dense = _sample(_square_edges(), 0.002)
    pol = np.where(rng.random(len(dense)) < 0.5, 1, -1)
    T = gt.matrices()
    prev = None
    cols: list[list[np.ndarray]] = [[], [], [], []]
    for k in range(len(gt)):
        Xc = (dense - T[k, :3, 3]) @ T[k, :3, :3]
        uv = np.rint(Xc[:, :2] / Xc[:, 2:3] * f + [cal.cx, cal.cy]).astype(np.int64)
        ok = (Xc[:, 2] > 0.05) & (uv[:, 0] >= 0) & (uv[:, 0] < width) & (uv[:, 1] >= 0) & (uv[:, 1] < height)
        code = np.where(ok, uv[:, 1] * width + uv[:, 0], -1)
        if prev is not None:
            idx = np.flatnonzero((code != prev) & (code >= 0))
            _, first = np.unique(code[idx], return_index=True)
            idx = idx[np.sort(first)]
            for col, v in zip(cols, (gt.t[k - 1] + rng.integers(0, 500, idx.size), uv[idx, 0], uv[idx, 1], pol[idx])):
                col.append(v)
        prev = code
    t, x, y, p = (np.concatenate(c) for c in cols)
    order = np.argsort(t, kind="stable")
    events = EventArray.from_arrays(t[order], x[order], y[order], p[order])
    imu = ImuSamples.from_arrays(gt.t[::5], np.tile([0, 0, 9.81], (len(gt.t[::5]), 1)), np.zeros((len(gt.t[::5]), 3)))
    rec = Recording(events, imu, gt, cal, {"scene": "squares"})
    return rec, ContourMap.from_points(_sample(_square_edges(), 0.01))


def old_and_recent_entries(folder, file_name: str, size: int) -> None:
    """Two disk-cache entries, ``old`` used before ``recent``, each holding one file of ``size`` bytes."""
    import os

    for i, name in enumerate(("old", "recent")):
        d = folder / name
        d.mkdir(parents=True)
        (d / "meta.json").write_text("{}")
        (d / file_name).write_bytes(b"x" * size)
        os.utime(d / "meta.json", (1000 + i, 1000 + i))


def write_squares_root(root, squares_scene):
    """Write the squares recording and its map into ``root`` (``squares.h5``, ``squares_map.ply``); returns ``root``."""
    from evpose.io.h5 import write_recording_h5
    from evpose.io.map_ply import write_contour_map

    rec, cmap = squares_scene
    write_recording_h5(root / "squares.h5", rec)
    write_contour_map(root / "squares_map.ply", cmap)
    return root


def write_data_root(root, squares_scene, corrupt_bytes: bytes = b"\x89HDF\r\n\x1a\n broken"):
    """Fill ``root`` as a viewer data directory: the squares recording with its map, the map-less sweeping bar and a
    corrupt ``.h5`` (listed as unreadable)."""
    from evpose.io.h5 import write_recording_h5

    write_squares_root(root, squares_scene)
    write_recording_h5(root / "bar.h5", sweeping_bar_recording())
    (root / "corrupt.h5").write_bytes(corrupt_bytes)
    return root
