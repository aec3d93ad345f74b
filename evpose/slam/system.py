"""The SLAM system: events -> tiny windows -> MCIs -> KLT tracks -> two-view init / local-map tracking -> keyframes, local BA -> atlas.

Everything runs in one thread in a fixed order (the paper's implementation uses
threads and is, by its own README, unstable); OpenCV's RANSAC generator is
re-seeded before every call, so a run repeats bit for bit.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.camera import CameraCalibration
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory, invert_pose
from evpose.errors import InputError
from evpose.slam.atlas import Atlas, Keyframe, MapPoint, SlamMap
from evpose.slam.bundle_adjustment import local_bundle_adjustment
from evpose.slam.config import SlamConfig, SlamMode
from evpose.slam.event_window import EventWindowSelector, ReconstructionWindow, WindowEvent
from evpose.slam.features import detect_features, track_features
from evpose.slam.inertial import initialize_imu
from evpose.slam.inertial_ba import InertialState, inertial_local_bundle_adjustment
from evpose.slam.initialization import initialize_two_view
from evpose.slam.local_map import cull_points, insert_keyframe, need_keyframe, triangulate_new_points
from evpose.slam.mci import MciGenerator, MciResult, MotionPrior
from evpose.slam.step_result import SlamStatus, SlamStepResult
from evpose.slam.tracking import estimate_pose

_WINDOW_REASONS = {
    WindowEvent.WAITING: "collecting events",
    WindowEvent.LOW_RATE: "event rate below th_e (camera still or too slow)",
    WindowEvent.NO_TEXTURE: "too few features in the tiny frames (no texture)",
    WindowEvent.TRACKING: "tracking features in tiny frames",
    WindowEvent.DISPATCHED: "",
}


@dataclass
class _Frontend:
    """KLT tracks on MCIs and the association of tracks with map points."""

    ids: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    uv: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.float32))
    prev8: np.ndarray | None = None
    next_id: int = 0
    track_to_point: dict = field(default_factory=dict)
    init_ref: dict | None = None
    """Track id -> pixel in the initialisation reference MCI."""
    init_ref_t: int = 0
    init_frames: int = 0


class EventSlam:
    """Map-free event(-inertial) SLAM. Feed events with :meth:`step`; read maps from :attr:`atlas`."""

    def __init__(self, config: SlamConfig, calibration: CameraCalibration, imu: ImuSamples | None = None):
        if calibration is None:
            raise InputError(None, "SLAM needs a camera calibration")
        if config.mode is SlamMode.EVENT_INERTIAL and (imu is None or len(imu) < 2):
            raise InputError(None, "event-inertial mode needs IMU samples; the recording has none")
        self.cfg = config
        self.calib = calibration
        self.imu = imu if config.mode is SlamMode.EVENT_INERTIAL else None
        self.K = calibration.K
        self.width, self.height = calibration.width, calibration.height
        self._table = calibration.undistortion_table if calibration.model.value != "none" else None
        self.window = EventWindowSelector(config.window, config.features, config.image, self.width, self.height, config.seed)
        self.mci_gen = MciGenerator(config.mci, config.image, self.K, self.width, self.height, config.seed)
        self.atlas = Atlas()
        self.fe = _Frontend()
        self.results: list[SlamStepResult] = []
        """One result per processed MCI."""
        self._next_point = 0
        self._state = SlamStatus.NOT_INITIALISED
        self._last_t = 0
        self.last_imu_init = None
        """Outcome of the last IMU initialisation attempt (event-inertial mode)."""

    # --------------------------------------------------------------- public
    def step(self, events: EventArray) -> SlamStepResult:
        """Consume a batch of sensor events; returns the result of the last MCI made from them (or the waiting state)."""
        if len(events):
            self._last_t = int(events.t[-1])
        x = events.x.astype(np.float64)
        y = events.y.astype(np.float64)
        if self._table is not None and len(events):
            # Events are undistorted before use (paper section V); K stays that of the ideal pinhole.
            uv = self._table[events.y.astype(np.intp), events.x.astype(np.intp)]
            x, y = uv[:, 0].astype(np.float64), uv[:, 1].astype(np.float64)
        windows = self.window.push(events.t, x, y, events.p)
        last = None
        for rw in windows:
            last = self._process_window(rw)
            self.results.append(last)
        if last is None:
            m = self.atlas.active
            reason = _WINDOW_REASONS[self.window.last_event]
            last = SlamStepResult(self._last_t, SlamStatus.WAITING, reason, map_id=m.id if m else -1, tiny_frame=self.window.last_tiny_image, n_events_window=self.window.n_events)
        else:
            last.mcis = len(windows)
            last.tiny_frame = self.window.last_tiny_image
        return last

    def snapshot(self) -> dict:
        """A deep copy of all mutable state; :meth:`restore` returns the system to it exactly (viewer seeking)."""
        import copy

        return copy.deepcopy({
            "window": self.window.state, "last_tiny": self.window.last_tiny_image, "last_event": self.window.last_event,
            "n_hist": self.window.n_events_history, "atlas": self.atlas, "fe": self.fe, "next_point": self._next_point,
            "state": self._state, "last_t": self._last_t, "imu_init": self.last_imu_init, "n_results": len(self.results),
        })

    def restore(self, snap: dict) -> None:
        import copy

        s = copy.deepcopy(snap)
        self.window.state, self.window.last_tiny_image, self.window.last_event = s["window"], s["last_tiny"], s["last_event"]
        self.window.n_events_history = s["n_hist"]
        self.atlas, self.fe, self._next_point = s["atlas"], s["fe"], s["next_point"]
        self._state, self._last_t, self.last_imu_init = s["state"], s["last_t"], s["imu_init"]
        del self.results[s["n_results"]:]

    # ------------------------------------------------------------- pipeline
    def _prior(self, rw: ReconstructionWindow) -> MotionPrior:
        prior = MotionPrior()
        m = self.atlas.active
        if self._state is SlamStatus.OK and m is not None and len(m.traj_t) >= 2:
            dt = (m.traj_t[-1] - m.traj_t[-2]) / 1e6
            if dt > 0:
                D = invert_pose(m.traj_T[-2]) @ m.traj_T[-1]
                prior.omega = Rotation.from_matrix(D[:3, :3]).as_rotvec() / dt
                prior.velocity = D[:3, 3] / dt
            T_cw = invert_pose(m.traj_T[-1])
            pids = [self.fe.track_to_point[t] for t in self.fe.ids.tolist() if t in self.fe.track_to_point]
            if pids:
                Xw = np.stack([m.points[p].xyz for p in pids if p in m.points] or [np.full(3, np.nan)])
                z = Xw @ T_cw[2, :3] + T_cw[2, 3]
                z = z[np.isfinite(z) & (z > 0)]
                prior.map_depth = float(np.median(z)) if z.size else None
        if self.imu is not None:
            # Gyro mean over the window, rotated into the camera frame: the rotation part of H3.
            off = self.calib.time_offset_us
            w = self.imu.time_window(int(rw.t[0]) + off, int(rw.t[-1]) + off + 1)
            if len(w):
                st = m.inertial if m is not None and m.imu_initialised else None
                bias = st.bias_gyro if st is not None else np.zeros(3)
                prior.omega = self.calib.T_cam_imu[:3, :3] @ (w.gyro.mean(axis=0) - bias)
                if prior.velocity is None:
                    prior.velocity = np.zeros(3)
        return prior

    def _track_mci(self, mci: MciResult) -> None:
        fe = self.fe
        if fe.prev8 is not None and len(fe.ids):
            new, ok = track_features(fe.prev8, mci.image8, fe.uv, self.cfg.features)
            fe.ids, fe.uv = fe.ids[ok], new[ok]
        fe.prev8 = mci.image8

    def _replenish(self, img8: np.ndarray) -> None:
        fe = self.fe
        if len(fe.ids) >= self.cfg.features.target_tracks:
            return
        pts = detect_features(img8, self.cfg.features, existing=fe.uv, max_total=self.cfg.features.target_tracks - len(fe.ids))
        if len(pts):
            fe.ids = np.concatenate([fe.ids, np.arange(fe.next_id, fe.next_id + len(pts), dtype=np.int64)])
            fe.uv = np.concatenate([fe.uv, pts.astype(np.float32)])
            fe.next_id += len(pts)

    def _process_window(self, rw: ReconstructionWindow) -> SlamStepResult:
        t0, c0 = time.perf_counter(), time.thread_time()
        mci = self.mci_gen.generate(rw, self._prior(rw))
        t1, c1 = time.perf_counter(), time.thread_time()
        self._track_mci(mci)
        keyframe = False
        if self._state is SlamStatus.OK:
            status, reason, pose, keyframe = self._track_map(mci)
        else:
            status, reason, pose = self._try_initialise(mci)
        t2, c2 = time.perf_counter(), time.thread_time()
        self._replenish(mci.image8)
        m = self.atlas.active
        fe = self.fe
        has_pt = np.array([t in fe.track_to_point for t in fe.ids.tolist()], bool)
        t3 = time.perf_counter()
        return SlamStepResult(
            t_us=mci.t_us, status=status, reason=reason, pose=pose, map_id=m.id if m else -1,
            mci=mci.image, hypothesis=mci.hypothesis.value, hypothesis_scores=dict(mci.scores),
            features=fe.uv.copy(), feature_ids=fe.ids.copy(), feature_has_point=has_pt, keyframe=keyframe,
            map_points=m.point_array() if m is not None and status is SlamStatus.OK else None,
            n_events_window=self.window.n_events,
            # Wall times, plus this thread's CPU times (immune to other processes on shared cores).
            timings_ms={"mci": (t1 - t0) * 1e3, "tracking": (t2 - t1) * 1e3, "total": (t3 - t0) * 1e3,
                        "mci_cpu": (c1 - c0) * 1e3, "tracking_cpu": (c2 - c1) * 1e3},
            counts={"tracks": int(len(fe.ids)), "map_points": int(len(m.points)) if m else 0, "keyframes": int(len(m.keyframes)) if m else 0, "events": int(mci.n_events)},
        )

    # ------------------------------------------------------- initialisation
    def _try_initialise(self, mci: MciResult) -> tuple[SlamStatus, str, np.ndarray | None]:
        fe, icfg = self.fe, self.cfg.initialization
        if fe.init_ref is None:
            self._replenish(mci.image8)
            fe.init_ref = {int(t): uv.astype(np.float64) for t, uv in zip(fe.ids.tolist(), fe.uv)}
            fe.init_ref_t, fe.init_frames = mci.t_us, 0
            return SlamStatus.NOT_INITIALISED, f"initialisation reference set with {len(fe.init_ref)} features", None
        fe.init_frames += 1
        common = [i for i, t in enumerate(fe.ids.tolist()) if t in fe.init_ref]
        ids = fe.ids[common]
        p1 = np.array([fe.init_ref[int(t)] for t in ids]).reshape(-1, 2)
        p2 = fe.uv[common].astype(np.float64)
        res = initialize_two_view(self.K, p1, p2, icfg, self.cfg.seed)
        if not res.ok:
            if fe.init_frames >= icfg.max_frames or len(common) < icfg.min_matches:
                fe.init_ref = None  # start over from the next MCI with fresh features
            return SlamStatus.NOT_INITIALISED, f"initialisation: {res.reason}", None
        m = self.atlas.new_map() if (self.atlas.active is None or self.atlas.active.keyframes) else self.atlas.active
        kf0 = Keyframe(0, fe.init_ref_t, np.eye(4), {int(t): fe.init_ref[int(t)].copy() for t in ids})
        kf1 = Keyframe(1, mci.t_us, res.T_wc2, {int(t): uv.astype(np.float64) for t, uv in zip(fe.ids.tolist(), fe.uv)})
        m.keyframes = [kf0, kf1]
        fe.track_to_point = {}
        for k in np.flatnonzero(res.good):
            tid = int(ids[k])
            pid = self._next_point
            self._next_point += 1
            m.points[pid] = MapPoint(pid, res.points[k].copy(), {0: p1[k].copy(), 1: p2[k].copy()}, tid, 1)
            fe.track_to_point[tid] = pid
        tc = self.cfg.tracking
        # Global BA of the two-view map (both keyframes' poses fixed: they define frame and scale).
        local_bundle_adjustment(m, self.K, 2, tc.ba_iterations, tc.ba_huber_px, n_fixed=2)
        cull_points(m, self.K, fe.track_to_point, tc)
        m.add_pose(kf0.t_us, kf0.T_wc)
        m.add_pose(kf1.t_us, kf1.T_wc)
        fe.init_ref = None
        self._state = SlamStatus.OK
        return SlamStatus.OK, f"map {m.id} initialised ({res.model}, {len(m.points)} points, parallax {res.median_parallax_deg:.1f} deg)", m.keyframes[-1].T_wc.copy()

    def _try_imu_init(self, m: SlamMap) -> None:
        """Scale the map to metres and align it with gravity once enough keyframes span enough time."""
        if not _imu_init_due(m, self.cfg.inertial):
            return
        kfs = m.keyframes
        res = initialize_imu([k.t_us for k in kfs], [k.T_wc for k in kfs], self.imu, self.calib.T_cam_imu, self.calib.time_offset_us, self.cfg.inertial)
        self.last_imu_init = res
        if res.ok:
            m.transform(res.R_align, res.scale)
            m.imu_initialised = True
            m.scale = res.scale
            m.inertial = InertialState({kf.id: v for kf, v in zip(kfs, res.velocities)}, np.zeros(3), res.gyro_bias.copy())

    # ------------------------------------------------------------- tracking
    def _lose(self, reason: str) -> tuple[SlamStatus, str, None, bool]:
        m = self.atlas.active
        if m is not None:
            m.lost_reason = reason
        self._state = SlamStatus.NOT_INITIALISED
        self.fe.track_to_point = {}
        self.fe.init_ref = None
        # The next successful initialisation opens a new map of the atlas.
        self.atlas.new_map()
        return SlamStatus.LOST, f"tracking lost: {reason}", None, False

    def _track_map(self, mci: MciResult) -> tuple[SlamStatus, str, np.ndarray | None, bool]:
        m, fe, tc = self.atlas.active, self.fe, self.cfg.tracking
        sel = [i for i, t in enumerate(fe.ids.tolist()) if fe.track_to_point.get(t) in m.points]
        if len(sel) < tc.min_inliers:
            return self._lose(f"{len(sel)} tracked map points < {tc.min_inliers}")
        Xw = np.stack([m.points[fe.track_to_point[int(fe.ids[i])]].xyz for i in sel])
        uv = fe.uv[sel].astype(np.float64)
        guess = m.traj_T[-1]
        if len(m.traj_t) >= 2:
            # Constant-velocity prediction, scaled to this MCI's time step.
            D = invert_pose(m.traj_T[-2]) @ m.traj_T[-1]
            dt_prev = max(m.traj_t[-1] - m.traj_t[-2], 1)
            a = (mci.t_us - m.traj_t[-1]) / dt_prev
            if 0 < a < 4:
                Dr = Rotation.from_matrix(D[:3, :3]).as_rotvec() * a
                Da = np.eye(4)
                Da[:3, :3] = Rotation.from_rotvec(Dr).as_matrix()
                Da[:3, 3] = D[:3, 3] * a
                guess = m.traj_T[-1] @ Da
        est = estimate_pose(self.K, Xw, uv, guess, tc, self.cfg.seed)
        if not est.ok:
            return self._lose(est.reason)
        for k in np.flatnonzero(~est.inliers):
            fe.track_to_point.pop(int(fe.ids[sel[k]]), None)
        T_wc = est.T_wc
        m.add_pose(mci.t_us, T_wc)
        n_tracked = int(est.inliers.sum())
        keyframe = False
        if need_keyframe(m, fe.ids, fe.uv, n_tracked, tc):
            keyframe = True
            kf = insert_keyframe(m, mci.t_us, T_wc, fe.ids, fe.uv.astype(np.float64), fe.track_to_point)
            self._next_point = triangulate_new_points(m, self.K, kf, fe.track_to_point, tc, self._next_point)
            ic = self.cfg.inertial
            if m.imu_initialised and ic.inertial_ba:
                inertial_local_bundle_adjustment(m, m.inertial, self.K, self.imu, self.calib.T_cam_imu, self.calib.time_offset_us,
                                                 tc.local_window, tc.ba_iterations, tc.ba_huber_px, ic.acc_noise, ic.gyro_noise)
            else:
                local_bundle_adjustment(m, self.K, tc.local_window, tc.ba_iterations, tc.ba_huber_px, n_fixed=1)
            cull_points(m, self.K, fe.track_to_point, tc)
            # BA moved the newest keyframe: the trajectory's last pose follows it.
            m.add_pose(mci.t_us, m.keyframes[-1].T_wc)
            if self.imu is not None and not m.imu_initialised:
                self._try_imu_init(m)
            T_wc = m.keyframes[-1].T_wc
        return SlamStatus.OK, f"{n_tracked} inliers, rms {est.rms_px:.2f} px", T_wc.copy(), keyframe


def _imu_init_due(m: SlamMap, cfg) -> bool:
    kfs = m.keyframes
    return len(kfs) >= cfg.init_keyframes and (kfs[-1].t_us - kfs[0].t_us) / 1e6 >= cfg.init_min_span_s


@dataclass
class SlamRun:
    """Everything a run produced."""

    results: list[SlamStepResult]
    """One per processed MCI."""
    atlas: Atlas
    duration_s: float
    """Span of the recording's events, seconds."""
    wall_s: float
    """Wall time of the run, seconds."""

    def trajectories(self) -> list[Trajectory]:
        return self.atlas.trajectories()


def run_slam(recording: Recording, config: SlamConfig, chunk_us: int = 5000, slam: EventSlam | None = None) -> SlamRun:
    """Run SLAM over a whole recording, feeding events in ``chunk_us`` slices."""
    if recording.calibration is None:
        raise InputError(recording.source, "the recording has no camera calibration; SLAM needs one")
    slam = slam or EventSlam(config, recording.calibration, recording.imu)
    ev = recording.events
    t_start = time.perf_counter()
    if len(ev):
        t0, t1 = int(ev.t[0]), int(ev.t[-1])
        edges = np.arange(t0, t1 + chunk_us, chunk_us, dtype=np.int64)
        idx = np.searchsorted(ev.t, edges, side="left")
        idx[-1] = len(ev)
        for a, b in zip(idx[:-1], idx[1:]):
            if b > a:
                slam.step(ev[a:b])
    return SlamRun(slam.results, slam.atlas, ev.duration_us / 1e6, time.perf_counter() - t_start)
