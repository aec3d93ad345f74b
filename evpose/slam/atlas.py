"""Maps of keyframes and points, and the atlas of disconnected maps a run leaves behind."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evpose.core.trajectory import Trajectory
from evpose.slam.pose_refit import PoseObservations, first_pose_extrapolated, keyframe_interpolated, refit_trajectory


@dataclass
class Keyframe:
    id: int
    t_us: int
    """Time of the MCI the keyframe was made from, us."""
    T_wc: np.ndarray
    """Pose ``T_world_cam`` (4, 4), map units."""
    obs: dict[int, np.ndarray] = field(default_factory=dict)
    """Track id -> ideal-pinhole pixel (2,) in this keyframe."""
    image8: np.ndarray | None = None
    """The keyframe's MCI (uint8) while the keyframe is in the local window, for KLT re-finding of its points; else None."""
    R_cm: np.ndarray | None = None
    """Camera-from-room rotation (3, 3) measured from the MCI's axis-aligned edges, or None (:mod:`evpose.slam.room_axes`)."""
    R_cm_info: np.ndarray | None = None
    """Information (3, 3) of ``R_cm`` as a camera-frame rotation, 1/rad^2."""
    visual: bool = True
    """Placed by the images (PnP, a two-view map), not coasted or IMU-predicted (``InertialConfig.init_visual``)."""


@dataclass
class MapPoint:
    id: int
    xyz: np.ndarray
    """World position (3,), map units."""
    obs: dict[int, np.ndarray] = field(default_factory=dict)
    """Keyframe id -> observed pixel (2,)."""
    track_id: int = -1
    """Feature track that observes it (KLT tracks carry associations, no descriptors)."""
    created_kf: int = 0
    patch: np.ndarray | None = None
    """Template (uint8, square) around the point's newest keyframe observation, for re-finding it by projection."""


@dataclass
class SlamMap:
    """One connected map: keyframes, points and the per-MCI trajectory, in its own frame and scale."""

    id: int
    keyframes: list[Keyframe] = field(default_factory=list)
    points: dict[int, MapPoint] = field(default_factory=dict)
    traj_t: list[int] = field(default_factory=list)
    traj_T: list[np.ndarray] = field(default_factory=list)
    """Per-MCI poses as estimated online (``T_world_cam``)."""
    traj_ref: list[int] = field(default_factory=list)
    """Per-MCI reference keyframe id (the newest keyframe when the pose was added; -1 without one)."""
    traj_rel: list[np.ndarray] = field(default_factory=list)
    """Per-MCI pose relative to its reference keyframe, ``T_kf^-1 T_wc``: later BA moves of the keyframe carry the pose along."""
    imu_initialised: bool = False
    """Event-inertial mode: the map was scaled to metres and gravity-aligned by the IMU initialisation."""
    scale: float = 1.0
    """Metres per original map unit applied by the IMU initialisation (and its refinement)."""
    imu_init_t_us: int = -1
    """Time of the keyframe at which the IMU initialisation succeeded, us (-1 before)."""
    scale_refined: bool = False
    """Event-inertial mode: the scale and gravity were re-estimated once over a longer stretch (``InertialConfig.refine_after_s``)."""
    inertial: object = None
    """:class:`evpose.slam.inertial_ba.InertialState` once the IMU is initialised."""
    lost_reason: str = ""
    """Why tracking of this map ended ("" while active or at the end of the recording)."""
    restructured: int = 0
    """Times the map was re-initialised from a wide-baseline keyframe pair (:mod:`evpose.slam.map_restructure`)."""
    traj_obs: dict[int, PoseObservations] = field(default_factory=dict)
    """Per-MCI time (us) -> what placed the pose by PnP (inliers, other tracks); recorded only while ``refit_K`` is set."""
    refit_K: np.ndarray | None = None
    """Camera matrix with which :meth:`trajectory` re-solves the PnP-placed poses on the points' current positions
    (:mod:`evpose.slam.pose_refit`, :attr:`TrackingConfig.refit_tracked_poses`); None: never."""
    refit_threshold_px: float = 2.5
    """Other tracks of a re-solved MCI join its inliers when they reproject within this, pixels."""
    interpolate_between_keyframes: bool = False
    """:meth:`trajectory` places each PnP-placed MCI between two keyframes on the keyframes' interpolated pose
    (:func:`evpose.slam.pose_refit.keyframe_interpolated`, :attr:`TrackingConfig.refit_keyframe_interpolation`)."""
    first_pose_span_us: int = 0
    """> 0: :meth:`trajectory` places the map's first pose by the motion of its next poses over this span, us
    (:func:`evpose.slam.pose_refit.first_pose_extrapolated`, :attr:`TrackingConfig.first_pose_extrapolation_s`)."""
    young_pose_us: int = 0
    """With ``first_pose_span_us``: every pose less than this after the map's first one is placed so as well, us
    (:attr:`TrackingConfig.young_pose_extrapolation_s`)."""
    traj_alt: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    """Per coasted MCI time (us) -> (its written pose ``T_world_cam`` as placed online, that pose relative to the coasted
    pose's reference keyframe): :meth:`trajectory` writes it in place of the coasted pose
    (:mod:`evpose.slam.written_coast`); empty unless ``VisualGyroConfig.written_coasts``."""
    segment_start_kf: int = 0
    """Id of the first keyframe of the map's newest visual segment: a lost map re-joined by the next two-view map
    (:mod:`evpose.slam.map_rejoin`) shares no points with it, and the visual local BA stays within the segment."""

    def keyframe(self, kf_id: int) -> Keyframe:
        for kf in self.keyframes:
            if kf.id == kf_id:
                return kf
        raise KeyError(kf_id)

    def add_pose(self, t_us: int, T_wc: np.ndarray) -> None:
        ref = self.keyframes[-1] if self.keyframes else None
        rel = np.linalg.solve(ref.T_wc, T_wc) if ref is not None else T_wc.copy()
        # Trajectories need strictly increasing times; a repeated MCI time replaces the old pose.
        if self.traj_t and t_us <= self.traj_t[-1]:
            self.traj_T[-1] = T_wc.copy()
            self.traj_ref[-1] = ref.id if ref is not None else -1
            self.traj_rel[-1] = rel
            alt = self.traj_alt.get(self.traj_t[-1])
            if alt is not None:
                # A keyframe made at the pose: the written alternative hangs from it too.
                self.traj_alt[self.traj_t[-1]] = (alt[0], np.linalg.solve(ref.T_wc, alt[0]) if ref is not None else alt[0].copy())
            return
        self.traj_t.append(int(t_us))
        self.traj_T.append(T_wc.copy())
        self.traj_ref.append(ref.id if ref is not None else -1)
        self.traj_rel.append(rel)

    def add_written_alternative(self, t_us: int, T_wc: np.ndarray) -> None:
        """Write ``T_wc`` in place of the pose just added at ``t_us`` (same reference keyframe, so later BA moves of it
        carry both alike); tracking keeps reading the added pose."""
        if not self.traj_t or self.traj_t[-1] != t_us:
            return
        ref = self.keyframe(self.traj_ref[-1]) if self.traj_ref[-1] >= 0 else None
        rel = np.linalg.solve(ref.T_wc, T_wc) if ref is not None else T_wc.copy()
        self.traj_alt[int(t_us)] = (T_wc.copy(), rel)

    def record_pose_observations(self, t_us: int, point_ids: np.ndarray, uv: np.ndarray, track_ids: np.ndarray, track_uv: np.ndarray,
                                 prior_sigmas: tuple[float, float] | None = None) -> None:
        """Keep what placed the pose at ``t_us`` by PnP (inliers' point ids and pixels, the MCI's other tracks, the
        sigmas of the motion prior it was refined with), when poses are re-solved later."""
        if self.refit_K is not None:
            # Pixels as the tracker holds them (float32): a long run keeps one entry per tracked MCI.
            self.traj_obs[int(t_us)] = PoseObservations(np.asarray(point_ids, np.int64).copy(), np.asarray(uv, np.float32).copy(),
                                                        np.asarray(track_ids, np.int64).copy(), np.asarray(track_uv, np.float32).copy(),
                                                        prior_sigmas)

    def transform(self, R: np.ndarray, s: float) -> None:
        """Apply ``x -> s R x`` to the whole map (keyframes, points, trajectory)."""
        def tf(T):
            out = T.copy()
            out[:3, :3] = R @ T[:3, :3]
            out[:3, 3] = s * (R @ T[:3, 3])
            return out

        for kf in self.keyframes:
            kf.T_wc = tf(kf.T_wc)
        for p in self.points.values():
            p.xyz = s * (R @ p.xyz)
        self.traj_T = [tf(T) for T in self.traj_T]
        for rel in self.traj_rel:
            rel[:3, 3] *= s  # a relative pose only feels the scale of a world transform
        for t, (T, rel) in list(self.traj_alt.items()):
            rel = rel.copy()
            rel[:3, 3] *= s
            self.traj_alt[t] = (tf(T), rel)

    def trajectory(self, refined: bool = True, refit: bool = True) -> Trajectory:
        """Per-MCI poses of this map as a :class:`Trajectory` (``T_world_cam``).

        ``refined`` (as ORB-SLAM saves its trajectories) composes each pose with the current pose of its
        reference keyframe, so corrections of later bundle adjustments reach the poses between
        keyframes, and with ``refit`` and ``refit_K`` set re-solves the PnP-placed poses on their inliers' current
        positions; otherwise the poses are those estimated online. The re-solve costs 0.3-0.6 ms per PnP pose (33 ms
        for the 79 poses of landing seed 0's map), so a caller that asks again at every step (the viewer's growing
        map) leaves it off.
        """
        if not self.traj_t:
            return Trajectory.empty()
        T = self.traj_T
        if refined:
            kf_pose = {kf.id: kf.T_wc for kf in self.keyframes}
            T = [kf_pose[r] @ rel if r in kf_pose else Tw for r, rel, Tw in zip(self.traj_ref, self.traj_rel, self.traj_T)]
            if refit and self.traj_alt:
                # Written coasted poses (evpose.slam.written_coast): output only, as the re-solve below.
                alt = self.traj_alt
                T = [(kf_pose[r] @ alt[t][1] if r in kf_pose else alt[t][0]) if t in alt else Tk
                     for t, r, Tk in zip(self.traj_t, self.traj_ref, T)]
            if refit and self.refit_K is not None and self.traj_obs:
                T = refit_trajectory(self.refit_K, self.traj_t, T, self.traj_obs, self.points, self.refit_threshold_px)
                if self.interpolate_between_keyframes:
                    T = keyframe_interpolated(self.traj_t, T, set(self.traj_obs),
                                              [kf.t_us for kf in self.keyframes], [kf.T_wc for kf in self.keyframes])
                if self.first_pose_span_us > 0:
                    # Only maps with PnP poses: a coasted map's poses hold one velocity, and its first pose moved onto
                    # their line left some maps exactly straight, which no Sim(3) aligns (evaluation drops them).
                    T = first_pose_extrapolated(self.traj_t, T, self.first_pose_span_us, self.young_pose_us)
        return Trajectory.from_matrices(np.array(self.traj_t, np.int64), np.stack(T))

    def point_array(self) -> np.ndarray:
        """All point positions (M, 3), ordered by point id."""
        if not self.points:
            return np.zeros((0, 3))
        return np.stack([self.points[k].xyz for k in sorted(self.points)])


@dataclass
class Atlas:
    """All maps of a run; a new one starts whenever tracking is lost and re-initialises."""

    maps: list[SlamMap] = field(default_factory=list)
    refit_K: np.ndarray | None = None
    """Given to every new map (:attr:`SlamMap.refit_K`)."""
    refit_threshold_px: float = 2.5
    """Given to every new map (:attr:`SlamMap.refit_threshold_px`)."""
    interpolate_between_keyframes: bool = False
    """Given to every new map (:attr:`SlamMap.interpolate_between_keyframes`)."""
    first_pose_span_us: int = 0
    """Given to every new map (:attr:`SlamMap.first_pose_span_us`)."""
    young_pose_us: int = 0
    """Given to every new map (:attr:`SlamMap.young_pose_us`)."""

    @property
    def active(self) -> SlamMap | None:
        return self.maps[-1] if self.maps else None

    def new_map(self) -> SlamMap:
        m = SlamMap(id=len(self.maps), refit_K=self.refit_K, refit_threshold_px=self.refit_threshold_px,
                    interpolate_between_keyframes=self.interpolate_between_keyframes, first_pose_span_us=self.first_pose_span_us,
                    young_pose_us=self.young_pose_us)
        self.maps.append(m)
        return m

    def trajectories(self) -> list[Trajectory]:
        """One trajectory per map that tracked at least one pose."""
        return [m.trajectory() for m in self.maps if m.traj_t]
