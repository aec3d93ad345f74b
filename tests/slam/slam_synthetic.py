"""A tiny synthetic event generator for SLAM tests: 3D points seen along a known trajectory, events splatted at their projections.

Each visible point emits events at a constant rate (independent of its image
speed), so a faster camera yields fewer events per pixel of motion, which is
what the ``N_e`` adaptation of Algorithm 1 reacts to. ``circle_pose`` / ``circle_map``: a camera circling
the origin, shared by the coasting and map re-join tests. ``sideways_map`` / ``inertial_truth_map``: small keyframe
maps for the bundle adjustment tests.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.camera import CameraCalibration
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory, invert_pose
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.event_image import event_image, to_uint8
from evpose.slam.geometry import project


def make_points(n: int, seed: int, depth=(3.0, 6.0), half_width: float = 3.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    z = rng.uniform(*depth, n)
    x = rng.uniform(-half_width, half_width, n)
    y = rng.uniform(-0.75 * half_width, 0.75 * half_width, n)
    return np.stack([x, y, z], axis=1)


def make_trajectory(duration_s: float, speed: float, rate_hz: float = 1000.0, yaw_rate: float = 0.05, seed: int = 0, shake: float = 0.0) -> Trajectory:
    """Sideways motion along x at ``speed`` m/s with a slow sinusoidal bob and yaw; ``shake`` (m) adds a 1 Hz back-and-forth that excites the accelerometer."""
    t = np.arange(0.0, duration_s + 1e-9, 1.0 / rate_hz)
    w = 2 * np.pi * 1.0
    pos = np.stack([speed * t - speed * duration_s / 2 + shake * np.sin(w * t), 0.05 * np.sin(2.0 * t) + 0.5 * shake * np.sin(0.7 * w * t), 0.1 * np.sin(1.3 * t)], axis=1)
    rot = Rotation.from_rotvec(np.stack([0.02 * np.sin(1.7 * t), yaw_rate * np.sin(1.1 * t), 0.01 * t], axis=1))
    return Trajectory.from_arrays((t * 1e6).astype(np.int64), pos, rot.as_quat())


def make_recording(duration_s: float = 1.0, speed: float = 0.4, n_points: int = 220, events_per_point_per_ms: float = 2.0,
                   width: int = 240, height: int = 180, seed: int = 0, calibration: CameraCalibration | None = None,
                   still: bool = False, noise_rate_hz: float = 2000.0, gyro_bias=(0.004, -0.003, 0.002), shake: float = 0.0) -> Recording:
    rng = np.random.default_rng(seed)
    calib = calibration or CameraCalibration(width, height, 200.0, 200.0, width / 2 - 0.5, height / 2 - 0.5)
    pts = make_points(n_points, seed)
    gt = make_trajectory(duration_s, 0.0 if still else speed, yaw_rate=0.0 if still else 0.05, shake=shake)
    if still:
        gt = Trajectory.from_arrays(gt.t, np.zeros_like(gt.position), np.tile([0, 0, 0, 1.0], (len(gt), 1)))
    T = gt.matrices()
    ts, xs, ys, ps = [], [], [], []
    step_us = 250
    lam = events_per_point_per_ms * step_us / 1000.0
    pol = np.where(rng.random(n_points) < 0.5, 1, -1)
    for t_us in range(0, int(duration_s * 1e6), step_us):
        k = min(int(t_us // 1000), len(T) - 1)
        T_cw = invert_pose(T[k])
        Xc = pts @ T_cw[:3, :3].T + T_cw[:3, 3]
        uv = calib.project(Xc)
        vis = (Xc[:, 2] > 0.1) & np.isfinite(uv).all(axis=1) & (uv[:, 0] > 0) & (uv[:, 0] < calib.width - 1) & (uv[:, 1] > 0) & (uv[:, 1] < calib.height - 1)
        counts = rng.poisson(lam, n_points) * vis
        if still:
            counts = rng.poisson(lam * 0.02, n_points) * vis  # a still camera: almost no events
        idx = np.repeat(np.arange(n_points), counts)
        if idx.size == 0:
            continue
        jitter = rng.normal(0.0, 0.35, (idx.size, 2))
        e_uv = np.rint(uv[idx] + jitter)
        ok = (e_uv[:, 0] >= 0) & (e_uv[:, 0] < calib.width) & (e_uv[:, 1] >= 0) & (e_uv[:, 1] < calib.height)
        tt = t_us + rng.integers(0, step_us, idx.size)
        ts.append(tt[ok]); xs.append(e_uv[ok, 0]); ys.append(e_uv[ok, 1]); ps.append(pol[idx][ok])
    n_noise = rng.poisson(noise_rate_hz * duration_s)
    ts.append(rng.integers(0, int(duration_s * 1e6), n_noise)); xs.append(rng.integers(0, calib.width, n_noise))
    ys.append(rng.integers(0, calib.height, n_noise)); ps.append(np.where(rng.random(n_noise) < 0.5, 1, -1))
    t = np.concatenate(ts); order = np.argsort(t, kind="stable")
    ev = EventArray.from_arrays(t[order], np.concatenate(xs)[order], np.concatenate(ys)[order], np.concatenate(ps)[order])
    # IMU = camera frame (T_cam_imu = I), 1 kHz, noise-free, plus a constant gyro bias. Gravity points
    # along +y of this world (the camera's "down" at rest): f = R^T (a_w - g_w).
    R = gt.rotation.as_matrix()
    dR = np.einsum("nji,njk->nik", R[:-1], R[1:])
    gyro = Rotation.from_matrix(dR).as_rotvec() / 1e-3 + gyro_bias
    gyro = np.vstack([gyro, gyro[-1:]])
    # Samples hold over [t_k, t_k+1): the forward-difference acceleration integrates back to the positions.
    v = np.diff(gt.position, axis=0) / 1e-3
    a_w = np.vstack([np.diff(v, axis=0) / 1e-3, np.zeros((2, 3))])
    acc = np.einsum("nji,nj->ni", R, a_w - np.array([0.0, 9.81, 0.0]))
    imu = ImuSamples.from_arrays(gt.t, acc, gyro)
    return Recording(events=ev, imu=imu, ground_truth=gt, calibration=calib, metadata={"scenario": "synthetic-points", "seed": seed})


def circle_pose(t_s: float, radius: float = 1.6, speed: float = 1.2) -> np.ndarray:
    """A camera circling the origin, looking outwards (the simulated room's motion)."""
    a = speed * t_s / radius
    T = np.eye(4)
    z = np.array([np.cos(a), np.sin(a), 0.0])
    y = np.array([0.0, 0.0, -1.0])
    T[:3, :3] = np.stack([np.cross(y, z), y, z], axis=1)
    T[:3, 3] = radius * z
    return T


def in_units(T: np.ndarray, units: float) -> np.ndarray:
    """``T`` with its translation expressed in units of ``units`` metres."""
    out = T.copy()
    out[:3, 3] /= units
    return out


def lost_circle_map(units: float, points_world: dict[int, np.ndarray]) -> SlamMap:
    """The circling camera's map lost at 60 ms (13 poses 5 ms apart), in units of ``units`` metres: one keyframe at
    t = 0 observing ``points_world`` (id -> world point, metres); what a re-join continues."""
    m = SlamMap(0)
    m.keyframes = [Keyframe(0, 0, in_units(circle_pose(0.0), units))]
    for i, X in points_world.items():
        m.points[i] = MapPoint(i, np.asarray(X, np.float64) / units, {0: np.zeros(2)})
    for k in range(13):
        m.add_pose(k * 5000, in_units(circle_pose(k * 0.005), units))
    return m


def circle_map(n: int, step_us: int) -> SlamMap:
    """A map whose trajectory is ``n`` poses of :func:`circle_pose`, ``step_us`` apart (no keyframes, no points)."""
    m = SlamMap(0)
    for k in range(n):
        m.add_pose(k * step_us, circle_pose(k * step_us / 1e6))
    return m


def shifted_image_pair(rng: np.random.Generator, shift, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Two 8-bit event images of random blobs and short segments, the second moved by ``shift`` px (some points leave
    the image): KLT inputs for comparing tracking implementations."""
    n = 3000
    x, y = rng.uniform(-20, width + 20, n), rng.uniform(-20, height + 20, n)
    seg = rng.uniform(0, 1, n)
    x, y = x + 6 * seg, y + 3 * seg
    a = to_uint8(event_image(x, y, None, width, height, 1.0))
    b = to_uint8(event_image(x + shift[0], y + shift[1], None, width, height, 1.0))
    return a, b


def sideways_map(rng: np.random.Generator, K: np.ndarray, n_kf: int, n_pts: int, step, point_noise: float,
                 perturb=None) -> tuple[SlamMap, np.ndarray, list[np.ndarray]]:
    """Keyframes ``k * step`` apart (turning 0.02 rad per keyframe about y) before points 3-6 units away, every point
    seen by every keyframe with 0.2 px noise; ``perturb(k, T)`` may move keyframe ``k``'s stored pose in place, and the
    stored points are ``point_noise`` off. Returns the map, the true points and the true poses."""
    X = np.c_[rng.uniform(-2, 2, n_pts), rng.uniform(-1.5, 1.5, n_pts), rng.uniform(3, 6, n_pts)]
    m = SlamMap(0)
    true_T = []
    for k in range(n_kf):
        T = np.eye(4)
        T[:3, :3] = Rotation.from_rotvec([0, 0.02 * k, 0]).as_matrix()
        T[:3, 3] = np.multiply(step, k)
        true_T.append(T)
        Tn = T.copy()
        if perturb is not None:
            perturb(k, Tn)
        m.keyframes.append(Keyframe(k, k * 1000, Tn, {}))
    for j in range(n_pts):
        obs = {k: project(K, invert_pose(T), X[j][None])[0][0] + rng.normal(0, 0.2, 2) for k, T in enumerate(true_T)}
        m.points[j] = MapPoint(j, X[j] + rng.normal(0, point_noise, 3), obs, j, 1)
    return m, X, true_T


def inertial_truth_map(rec: Recording, K: np.ndarray, idx, stretch: float = 1.0,
                       point_noise: float = 0.0) -> tuple[SlamMap, dict[int, np.ndarray]]:
    """Keyframes at samples ``idx`` of ``rec``'s truth, rotated so gravity (+y in the simulator) points along gtsam's
    -z, seeing 120 points (0.3 px noise, inside 240x180); positions and points stretched by ``stretch`` about the
    first keyframe (a map whose scale is off), points ``point_noise`` off. Returns the map and the keyframes' metric
    velocities from the truth."""
    R = Rotation.from_rotvec([-np.pi / 2, 0, 0]).as_matrix()
    gt = rec.ground_truth
    T = gt.matrices()
    X = make_points(120, 1) @ R.T
    m = SlamMap(0)
    rng = np.random.default_rng(0)
    vel = {}
    origin = R @ T[idx[0]][:3, 3]
    for k, i in enumerate(idx):
        Tw = T[i].copy()
        Tw[:3, :3] = R @ Tw[:3, :3]
        Tw[:3, 3] = R @ Tw[:3, 3]
        uv, z = project(K, invert_pose(Tw), X)
        inside = (z > 0) & (uv[:, 0] > 0) & (uv[:, 0] < 240) & (uv[:, 1] > 0) & (uv[:, 1] < 180)
        obs = {j: uv[j] + rng.normal(0, 0.3, 2) for j in np.flatnonzero(inside)}
        Ts = Tw.copy()
        if stretch != 1.0:
            Ts[:3, 3] = origin + stretch * (Tw[:3, 3] - origin)
        m.keyframes.append(Keyframe(k, int(gt.t[i]), Ts, {}))
        for j, o in obs.items():
            Xj = X[j] if stretch == 1.0 else origin + stretch * (X[j] - origin)
            if point_noise > 0:  # drawn for every observation, as the points are created on first sight
                Xj = Xj + rng.normal(0, point_noise, 3)
            m.points.setdefault(j, MapPoint(j, Xj, {}, j, 0)).obs[k] = o
        vel[k] = R @ ((gt.position[i + 1] - gt.position[i]) / 1e-3)
    return m, vel
