"""Which motion components each tracker mode plugs into the engine.

================  ====================  ==============================  =================
mode              pose prediction       field registration reads        output pose
================  ====================  ==============================  =================
``stpe``          Kalman, const. vel.   combined TDF                    registration
``stpe+filter``   Kalman, const. vel.   ``T_align`` (polarity filter)   registration
``full``          IMU fusion backend    ``T_align`` (polarity filter)   fused
================  ====================  ==============================  =================

The polarity filter predicts each used map point's polarity from the IMU
motion (:class:`~evpose.fusion.map_polarity_selector.MapPolaritySelector`) and builds
``T_align`` (:mod:`evpose.fusion.aligned_surface`): per point patch only the
events of the predicted polarity, nothing outside the patches (with
``polarity.drop_empty_points``, points whose patch shows no recent event are
not registered; off by default, see its docstring). ``polarity.event_filter =
False`` keeps the older per-point ON/OFF/combined fields over the whole box.

In ``stpe+filter`` a fusion backend still runs beside the registration, because
the polarity prediction needs the bias-corrected angular rate and the velocity;
its output is simply not the answer. ``fusion.backend`` picks the factor graph,
the EKF baseline or IMU-only dead reckoning. Like ``stpe``, it holds painted
points out of registration until the map refiner has placed them
(``map_refinement.hold_out_filtered``; their patches stay in ``T_align``), and
it reopens contradicted predictions (``polarity.reopen_contradicted_unfused``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.core.contour_map import ContourMap
from evpose.errors import InputError
from evpose.fusion import FusionMotionPredictor, MapPolaritySelector, PolarityPredictor, make_fusion
from evpose.fusion.ego_motion import EgoMotionFilter
from evpose.tracker.config import MotionModel, TrackerConfig, TrackerMode
from evpose.tracker.motion_filter import ConstantVelocityKalman
from evpose.tracker.predictor import ConstantPosePredictor, ConstantVelocityPredictor


@dataclass
class MotionComponents:
    """The pieces a mode adds to the bare STPE engine (all None in ``stpe`` mode)."""

    motion: FusionMotionPredictor | None = None
    """IMU fusion fed with every registration; source of angular rate and velocity."""
    polarity_selector: MapPolaritySelector | None = None
    ego_motion: EgoMotionFilter | None = None
    drives_pose: bool = False
    """True when ``motion`` is also the pose predictor and its fused estimate is the output."""


def build_motion_components(
    config: TrackerConfig,
    contour_map: ContourMap,
    calibration: CameraCalibration,
    has_imu: bool,
    initial_velocity_world: np.ndarray | None = None,
    source: str | None = None,
) -> MotionComponents:
    """Build what ``config.mode`` needs; raises InputError when the mode needs an IMU the recording lacks."""
    mode = TrackerMode(config.mode)
    if mode is TrackerMode.STPE:
        return MotionComponents()
    if not has_imu:
        raise InputError(source, f"mode {mode.value!r} needs IMU data (at least 2 samples) and the recording has fewer (use --mode stpe)")
    config.fusion.validate()
    motion = FusionMotionPredictor(make_fusion(config.fusion, calibration), None, initial_velocity_world)
    selector = None
    if config.polarity.enabled:
        selector = MapPolaritySelector(PolarityPredictor(config.polarity), contour_map, calibration.K, motion.fusion, calibration)
        selector.fused_pose = mode is TrackerMode.FULL
        if initial_velocity_world is None and selector.fused_pose:
            # The fused motion is unknown until the registrations have shown it: T_align composed from it would keep
            # only the events that agree with it (see PolarityFilterConfig.unknown_velocity_hold_updates).
            selector.hold_updates = int(config.polarity.unknown_velocity_hold_updates)
        if mode is TrackerMode.STPE_FILTER and config.polarity.unfused_latest_motion:
            selector.latest_state = motion
    ego = EgoMotionFilter(config.ego_motion) if (mode is TrackerMode.FULL and config.ego_motion.enabled) else None
    return MotionComponents(motion, selector, ego, drives_pose=mode is TrackerMode.FULL)


def unfused_predictor(config: TrackerConfig):
    """The motion model of the modes without IMU fusion (``config.motion_model``)."""
    if config.motion_model is MotionModel.CONSTANT_POSE:
        return ConstantPosePredictor()
    if config.motion_model is MotionModel.KALMAN:
        return ConstantVelocityKalman(config.motion_filter)
    return ConstantVelocityPredictor(window_us=int(round(float(config.velocity_window_ms) * 1e3)))
