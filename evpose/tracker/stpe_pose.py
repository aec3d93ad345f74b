"""How the unfused modes (``stpe``, ``stpe+filter``) turn one update's registration into the tracked pose.

The fused modes take the fusion backend's pose; here the motion model decides. With the constant-velocity Kalman
filter (:mod:`evpose.tracker.motion_filter`) a registration is a measurement the filter weighs against its
prediction, and a *weak* one (between ``weak_inlier_ratio`` and ``min_inlier_ratio`` of its points on recent events)
keeps the track only when it agrees with the motion model within ``weak_gate_sigma``. The other predictors copy a
successful registration into the track and coast on their prediction otherwise.
"""

from __future__ import annotations

import numpy as np

from evpose.tracker.motion_filter import ConstantVelocityKalman
from evpose.tracker.motion_filter_config import MotionFilterConfig
from evpose.tracker.predictor import MotionPredictor
from evpose.tracker.step_result import TrackStatus


def stpe_pose(predictor: MotionPredictor | ConstantVelocityKalman, config: MotionFilterConfig, until: int, reg, ok: bool,
              weak: bool, predicted: np.ndarray, reason: str) -> tuple[np.ndarray, TrackStatus, str, np.ndarray | None]:
    """(pose, status, reason, covariance) of the update at ``until`` from registration ``reg`` (accepted when ``ok``;
    ``weak`` when it passed only the weak inlier test); ``reason`` is the registration's, replaced when the motion
    model refuses it. ``covariance`` is the Kalman filter's, None for the other predictors."""
    if isinstance(predictor, ConstantVelocityKalman):
        if ok and weak:
            gate = float(config.weak_gate_sigma)
            pose = predictor.correct(until, reg.T_world_cam, reg.covariance, gate_sigma=gate)
            status = TrackStatus.OK if predictor.last_fused else TrackStatus.LOST
            if not predictor.last_fused:
                reason = (f"only {reg.inliers} of {reg.points_used} map points lie on recent events and the registration is "
                          f"{predictor.last_innovation_sigma:.1f} sigma from the motion model (need {gate:g})")
        elif ok:
            pose = predictor.correct(until, reg.T_world_cam, reg.covariance)
            status = TrackStatus.OK if predictor.last_fused else TrackStatus.DEGRADED
            if not predictor.last_fused:
                reason = f"registration {predictor.last_innovation_sigma:.1f} sigma from the motion model: not fused"
        else:
            pose = predictor.coast(until)
            status = TrackStatus.LOST
        return pose, status, reason, predictor.covariance()
    if ok:
        pose = reg.T_world_cam.copy()
        predictor.update(until, pose)
        return pose, TrackStatus.OK, reason, None
    # Keep coasting on the prediction so the next update can recover.
    return predicted.copy(), TrackStatus.LOST, reason, None
