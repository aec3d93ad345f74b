"""Metric maps of the event-inertial SLAM system (:class:`evpose.slam.system.EventSlam` inherits them).

The IMU initialisation of a map (scale and gravity, then one inertial BA over every keyframe), the one-off re-solve
of its scale, and the IMU's prediction of the camera pose from the newest keyframe. They read and write the system's
``imu``, ``calib``, ``K``, ``cfg`` and ``atlas`` (and ``last_imu_init`` / ``last_scale_refinement`` for the viewer).
"""

from __future__ import annotations

import numpy as np

from evpose.slam.atlas import SlamMap
from evpose.slam.inertial import imu_init_due, initialize_imu
from evpose.slam.inertial_ba import InertialState, inertial_local_bundle_adjustment
from evpose.slam.inertial_bridge import predict_camera_pose
from evpose.slam.inertial_init_visual import initialize_on_visual_keyframes
from evpose.slam.inertial_trajectory import carry_relative_scale, keyframe_positions, path_velocities
from evpose.slam.scale_refinement import refine_map_scale


class InertialMaps:
    """IMU initialisation, scale refinement and IMU pose prediction of :class:`evpose.slam.system.EventSlam` (a mixin:
    it owns no state of its own)."""

    def _try_imu_init(self, m: SlamMap) -> None:
        """Scale the map to metres and align it with gravity once enough keyframes span enough time."""
        if not imu_init_due([k.t_us for k in m.keyframes], self.cfg.inertial):
            return
        kfs = m.keyframes
        ic0 = self.cfg.inertial
        if ic0.init_visual.enabled:
            # InertialConfig.init_visual: coasted keyframes carry no true acceleration, older segments other scales.
            res = initialize_on_visual_keyframes(kfs, m.segment_start_kf, self.imu, self.calib.T_cam_imu, self.calib.time_offset_us, ic0)
        else:
            res = initialize_imu([k.t_us for k in kfs], [k.T_wc for k in kfs], self.imu, self.calib.T_cam_imu, self.calib.time_offset_us, ic0)
        if not res.ok and ic0.init_trailing_fallback and not ic0.init_visual.enabled:
            # InertialConfig.init_trailing_fallback: the map's older re-joined segments carry other scales; the newest
            # init_min_span_s of keyframes spans fewer re-joins.
            t0 = kfs[-1].t_us - int(ic0.init_min_span_s * 1e6)
            first = next(i for i, k in enumerate(kfs) if k.t_us >= t0)
            if first > 0 and len(kfs) - first >= ic0.init_keyframes:
                sub = kfs[first:]
                res2 = initialize_imu([k.t_us for k in sub], [k.T_wc for k in sub], self.imu, self.calib.T_cam_imu, self.calib.time_offset_us, ic0)
                if res2.ok:
                    res2.used = [first + k for k in res2.used]
                    res = res2
        self.last_imu_init = res
        if res.ok:
            m.transform(res.R_align, res.scale)
            m.imu_initialised = True
            m.imu_init_t_us = kfs[-1].t_us
            m.scale = res.scale
            m.inertial = InertialState({kfs[k].id: v for k, v in zip(res.used, res.velocities)}, np.zeros(3), res.gyro_bias.copy())
            ic, tc = self.cfg.inertial, self.cfg.tracking
            if ic.inertial_ba and ic.full_ba_after_init:
                before = keyframe_positions(m) if ic.carry_mci_scale else None
                # One inertial BA over every keyframe (as ORB-SLAM3 does after its initialisation): the IMU now
                # corrects the whole visual map, not only the next local window.
                inertial_local_bundle_adjustment(m, m.inertial, self.K, self.imu, self.calib.T_cam_imu, self.calib.time_offset_us,
                                                 len(m.keyframes), tc.ba_iterations, tc.ba_huber_px, ic.acc_noise, ic.gyro_noise,
                                                 ic.acc_bias_sigma, ic.gyro_bias_sigma, ic.velocity_from_imu,
                                             velocity_prior_sigma=ic.ba_velocity_prior_sigma, min_span_s=ic.ba_min_span_s, span_keyframes=ic.ba_span_keyframes,
                                                 marginals=ic.ba_window.velocity_marginal)
                if before is not None:
                    carry_relative_scale(m, before)
            self._path_velocities(m)
            self._reanchor_rotations(m)

    def _refine_scale(self, m: SlamMap) -> None:
        """Re-solve scale and gravity over all keyframes of a metric map, once (:mod:`evpose.slam.scale_refinement`)."""
        tc = self.cfg.tracking
        before = keyframe_positions(m)
        res = self.last_scale_refinement = refine_map_scale(m, self.K, self.imu, self.calib.T_cam_imu, self.calib.time_offset_us,
                                                            self.cfg.inertial, tc.ba_iterations, tc.ba_huber_px)
        if res.ok:
            if self.cfg.inertial.carry_mci_scale:
                # The similarity already scaled the relative poses; what is left is the BA's reshaping.
                carry_relative_scale(m, {k: res.scale * (res.R_align @ p) for k, p in before.items()})
            self._path_velocities(m)
            self._reanchor_rotations(m)

    def _path_velocities(self, m: SlamMap) -> None:
        """``InertialWindowConfig.init_velocity_span_s``: the keyframes' velocities from the map's own path, in place."""
        span = self.cfg.inertial.ba_window.init_velocity_span_s
        if span > 0 and m.inertial is not None:
            m.inertial.velocities.update(path_velocities(m.keyframes, self.calib.T_cam_imu, span))

    def _imu_prediction(self, t_us: int) -> np.ndarray | None:
        """``T_world_cam`` at ``t_us`` propagated by the IMU from the newest keyframe of a metric map, else None."""
        m = self.atlas.active
        if self.imu is None or m is None or not m.imu_initialised or m.inertial is None or not m.keyframes:
            return None
        ic = self.cfg.inertial
        pred = predict_camera_pose(m.keyframes[-1], m.inertial, self.imu, self.calib.T_cam_imu, self.calib.time_offset_us, t_us, ic.acc_noise, ic.gyro_noise)
        return None if pred is None else pred[0]
