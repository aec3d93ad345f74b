"""The gyro's aids to the event-inertial SLAM system (:class:`evpose.slam.system.EventSlam` inherits them).

KLT's start where the gyro rotation moves each feature, the gyro rotation between poses and keyframes, the visual
local BA's rotation-prior sigmas, and the pose re-solved with the gyro rotation as a prior; and, event-only, the rotation
priors from the MCIs' room-axis edges (:mod:`evpose.slam.room_axes`). They read the system's
``imu``, ``calib``, ``K``, ``cfg`` and ``atlas``; the event-only mode has no ``imu`` and gets None from each.
"""

from __future__ import annotations

import numpy as np

from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import SlamMap
from evpose.slam.event_coasting import camera_frame_rate, event_only_coast_pose
from evpose.slam.geometry import project
from evpose.slam.inertial_guards import bundle_keyframes
from evpose.slam.local_map import visual_ba_window
from evpose.slam.gyro_prior import (camera_delta_rotation, gyro_delta_rotation, keyframe_rotation_priors, reanchor_rotations,
                                    refine_pose_with_rotation_prior, rotation_angle_deg, sparse_pair_sigmas)
from evpose.slam.room_axes import measure_room_rotation, room_frame, room_priors
from evpose.slam.pnp_motion_prior import refine_pose_with_pose_prior
from evpose.slam.tracking import PoseEstimate
from evpose.slam.visual_gyro import visual_rotation
from evpose.slam.written_coast import depth_in_view, written_coast_pose


class GyroAids:
    """Gyro-based helpers of :class:`evpose.slam.system.EventSlam` (a mixin: it owns no state)."""

    def _gyro_flow(self, t0_us: int, t1_us: int, uv: np.ndarray) -> np.ndarray | None:
        """Where the gyro rotation alone moves ``uv`` between two MCIs (the infinite homography ``K R^T K^-1``): KLT's start."""
        if not self.cfg.inertial.klt_gyro_prediction:
            return None
        dR_cam = self._gyro_camera_delta(t0_us, t1_us)
        if dR_cam is None:
            return None
        H = self.K @ dR_cam.T @ np.linalg.inv(self.K)
        q = np.c_[uv.astype(np.float64), np.ones(len(uv))] @ H.T
        return (q[:, :2] / q[:, 2:3]).astype(np.float32)

    def _reanchor_rotations(self, m: SlamMap, refs: set | None = None) -> None:
        # Before the initialisation the bias is unknown, but over one keyframe interval (tens of ms) a MEMS bias of a
        # few mrad/s turns the camera by hundredths of a degree: far less than the visual rotation error indoors.
        bias = m.inertial.bias_gyro if m.imu_initialised and m.inertial is not None else np.zeros(3)
        reanchor_rotations(m, self.imu, self.calib.T_cam_imu, self.calib.time_offset_us, bias, refs)

    def _coast_rotation(self, m: SlamMap, mci, R_prior: np.ndarray | None) -> np.ndarray | None:
        """Orientation a failed MCI bridges or coasts on: the gyro's (``R_prior``, event-inertial), else, event-only with
        :attr:`VisualGyroConfig.enabled`, the visual gyro's. Asked only once the MCI has failed: the visual gyro costs
        ~7 ms per MCI (indoor, 240x180), which the tracked MCIs need not pay."""
        if R_prior is None and self.imu is None and self.cfg.visual_gyro.enabled:
            return self._visual_gyro(m, mci)
        return R_prior

    def _written_coast(self, m: SlamMap, mci) -> np.ndarray | None:
        """Event-only with :attr:`VisualGyroConfig.written_coasts`: the pose to write for the coasted ``mci``
        (:mod:`evpose.slam.written_coast`), else None."""
        vg, tc = self.cfg.visual_gyro, self.cfg.tracking
        if not vg.written_coasts or vg.enabled or self.imu is not None:
            return None
        if vg.written_coasts_max_map_s > 0 and m.traj_t and (self._last_pnp_t - m.traj_t[0]) / 1e6 >= vg.written_coasts_max_map_s:
            return None  # a mature map: its coast is written as tracked
        prev8, prev_t = self._prev_mci

        def measure(dR0):
            if prev8 is None or not m.traj_t or m.traj_t[-1] != prev_t:
                return None
            return visual_rotation(prev8, mci.image8, self.K, dR0, vg)

        return written_coast_pose(m, mci.t_us, int(tc.coast_span_s * 1e6), int(tc.coast_young_span_s * 1e6), measure,
                                  depth_in_view(m, self.K, mci.image8.shape) if tc.coast_written_parallax else None,
                                  int(tc.coast_written_velocity_span_s * 1e6), tc.coast_written_velocity_span_by_gap)

    def _visual_gyro(self, m: SlamMap, mci) -> np.ndarray | None:
        """Event-only: orientation at ``mci`` from the map's pose at the previous MCI and the rotation measured between the
        two MCIs' edges (:mod:`evpose.slam.visual_gyro`), started at the map's recent rate; None when the previous MCI
        has no pose in ``m`` or nothing was measured."""
        prev8, prev_t = self._prev_mci
        if prev8 is None or not m.traj_t or m.traj_t[-1] != prev_t:
            return None
        w = camera_frame_rate(m, int(self.cfg.tracking.coast_span_s * 1e6))
        dR0 = np.eye(3) if w is None else Rotation.from_rotvec(w * (mci.t_us - prev_t)).as_matrix()
        dR = visual_rotation(prev8, mci.image8, self.K, dR0, self.cfg.visual_gyro)
        return None if dR is None else m.traj_T[-1][:3, :3] @ dR

    def _gyro_rotation(self, t0_us: int, t1_us: int, T_wc0: np.ndarray) -> np.ndarray | None:
        """Camera orientation at ``t1`` predicted from ``T_wc0`` at ``t0`` by the gyro (event-inertial mode), else None."""
        dR_cam = self._gyro_camera_delta(t0_us, t1_us)
        return None if dR_cam is None else T_wc0[:3, :3] @ dR_cam

    def _gyro_camera_delta(self, t0_us: int, t1_us: int) -> np.ndarray | None:
        """Camera rotation from ``t0`` to ``t1`` integrated from the gyro (bias-corrected once the IMU is initialised), else None."""
        if self.imu is None:
            return None
        m = self.atlas.active
        bias = m.inertial.bias_gyro if m is not None and m.imu_initialised and m.inertial is not None else None
        off = self.calib.time_offset_us
        dR = gyro_delta_rotation(self.imu, int(t0_us) + off, int(t1_us) + off, bias)
        return None if dR is None else camera_delta_rotation(dR, self.calib.T_cam_imu)

    def _keyframe_rotation_priors(self, m: SlamMap) -> dict | None:
        """Gyro rotations between consecutive keyframes of the BA window (event-inertial mode), else None."""
        if self.imu is None or self.cfg.inertial.gyro_prior_uninit_deg <= 0:
            return None
        kfs = m.keyframes[-(self.cfg.tracking.local_window + 1):]
        if self.cfg.inertial.ba_gyro_prior_chain:
            # The BA leaves out keyframes that see no point (coasted ones): chain the gyro across them.
            kfs = bundle_keyframes(m, kfs, visual_ba_window(m, self.cfg.tracking, event_only=False)[0])
        return keyframe_rotation_priors(kfs, self.imu, self.calib.T_cam_imu, self.calib.time_offset_us) or None

    def _ba_rotation_sigmas(self, m: SlamMap, priors: dict | None) -> tuple[float, dict | None]:
        """Sigma (rad) of the visual BA's gyro rotation priors, and per-pair exceptions (``ba_gyro_prior_min_points``)."""
        ic = self.cfg.inertial
        loose = np.radians(max(ic.gyro_prior_uninit_deg, 1e-6))
        if ic.ba_gyro_prior_uninit_deg <= 0:
            return loose, None
        tight = np.radians(max(ic.ba_gyro_prior_uninit_deg, 1e-6))
        if ic.ba_gyro_prior_min_points <= 0 or not priors:
            return tight, None
        return tight, sparse_pair_sigmas(m, priors, ic.ba_gyro_prior_min_points, loose)

    def _refine_with_gyro(self, est, Xw: np.ndarray, uv: np.ndarray, R_wc_prior: np.ndarray, sigma_deg: float):
        """Re-solve the pose with the gyro rotation as a prior (planar scenes confuse tilt with shift; the gyro does not)."""
        tc = self._pose_tc(self.atlas.active)
        inl = est.inliers
        T_cw = refine_pose_with_rotation_prior(self.K, Xw[inl], uv[inl], invert_pose(est.T_wc), R_wc_prior.T,
                                               np.radians(sigma_deg), huber_px=tc.ba_huber_px)
        proj, z = project(self.K, T_cw, Xw)
        err = np.linalg.norm(proj - uv, axis=1)
        inliers = (z > 0) & (err < tc.reprojection_threshold_px)
        if inliers.sum() < max(tc.min_inliers, tc.min_inlier_ratio * len(Xw)):
            lim = self.cfg.inertial.max_gyro_disagreement_deg
            off = rotation_angle_deg(R_wc_prior, est.T_wc[:3, :3]) if lim > 0 and not self.atlas.active.imu_initialised else 0.0
            if off > lim > 0:
                # Over one MCI step the gyro's rotation is good to hundredths of a degree even with an unknown bias;
                # a visual pose degrees away is a bad association, and keeping it spikes the trajectory's rotation.
                return PoseEstimate(False, reason=f"visual rotation {off:.1f} deg off the gyro's")
            return est  # the prior disagrees with the images (a wrong bias or a bad time offset): keep the visual pose
        return PoseEstimate(True, invert_pose(T_cw), inliers, rms_px=float(np.sqrt(np.mean(err[inliers] ** 2))))

    def _measure_room(self, kf, img8: np.ndarray | None) -> None:
        """Event-only with ``TrackingConfig.ba_room_prior_deg``: a keyframe's camera-from-room rotation from its MCI (every
        keyframe, coasted or not, and the two of a new map, so a young map has its room frame)."""
        if self.imu is None and self.cfg.tracking.ba_room_prior_deg > 0 and img8 is not None and kf.R_cm is None:
            kf.R_cm, kf.R_cm_info = measure_room_rotation(img8, self.K)

    def _room_priors(self, m: SlamMap, window: int) -> dict | None:
        """Event-only with ``TrackingConfig.ba_room_prior_deg``: the rotation priors of the BA window against the map's
        room frame (:mod:`evpose.slam.room_axes`), else None."""
        if self.imu is not None or self.cfg.tracking.ba_room_prior_deg <= 0:
            return None
        M, labels = room_frame(m.keyframes)
        if M is None:
            return None
        tc = self.cfg.tracking
        return room_priors(m.keyframes[-window:], M, labels, np.radians(tc.ba_room_prior_deg), tc.ba_room_prior_gain) or None

    def _motion_prior_pose(self, m: SlamMap, t_us: int, est: PoseEstimate, Xw: np.ndarray, uv: np.ndarray) -> PoseEstimate:
        """Event-only: ``est`` refined with the map's predicted motion as a prior (``TrackingConfig.pnp_motion_prior_ratio``);
        ``est`` itself when the map has no motion to predict with or too few points agree with the refined pose."""
        tc = self._pose_tc(m)
        T_pred = event_only_coast_pose(m, t_us, int(tc.coast_span_s * 1e6))
        if T_pred is None:
            return est
        step = float(np.linalg.norm(T_pred[:3, 3] - m.traj_T[-1][:3, 3]))
        if not step > 0:
            return est
        sigmas = (np.radians(tc.pnp_motion_prior_deg), tc.pnp_motion_prior_ratio * step)
        inl = est.inliers
        T_cw = refine_pose_with_pose_prior(self.K, Xw[inl], uv[inl], invert_pose(est.T_wc), invert_pose(T_pred), *sigmas,
                                           huber_px=tc.ba_huber_px)
        proj, z = project(self.K, T_cw, Xw)
        err = np.linalg.norm(proj - uv, axis=1)
        inliers = (z > 0) & (err < tc.reprojection_threshold_px)
        if inliers.sum() < max(tc.min_inliers, tc.min_inlier_ratio * len(Xw)):
            return est
        return PoseEstimate(True, invert_pose(T_cw), inliers, rms_px=float(np.sqrt(np.mean(err[inliers] ** 2))), prior_sigmas=sigmas)
