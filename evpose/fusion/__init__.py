"""IMU fusion for EV-Pose (MHFO): gtsam preintegration, factor graph (iSAM2 + fixed lag), EKF and IMU-only baselines,
polarity prediction and ego-motion event filtering.

Public API::

    from evpose.fusion import FusionConfig, FusionBackend, make_fusion
    fusion = make_fusion(FusionConfig(), calibration)      # FactorGraphFusion | ErrorStateEkf | ImuOnlyPropagator
    fusion.add_imu(imu)                                     # ImuSamples on the IMU clock
    fusion.initialize(t_us, T_world_cam)                    # -> FusedState
    state = fusion.update(t_us, T_world_cam_registered, covariance_6x6)   # None pose = registration failed
    state = fusion.predict(t_us)                            # IMU propagation, no factor
    fusion.imu_rate_poses(t0_us, t1_us)                     # Trajectory at IMU sample times

    from evpose.fusion import PolarityPredictor, PolarityFilterConfig, MapPolaritySelector, classify_events
    from evpose.fusion import AlignedTimeSurface            # T_align: the polarity filter's output registration reads
    from evpose.fusion import EgoMotionFilter, EgoMotionConfig
    from evpose.fusion import FusionMotionPredictor         # a backend behind the tracker's MotionPredictor hook

gtsam is imported lazily by the backends, so importing this package is cheap.
"""

from evpose.fusion.aligned_surface import AlignedTimeSurface
from evpose.fusion.config import FusionBackend, FusionConfig, RegistrationErrorModel, RobustLoss
from evpose.fusion.ego_motion import EgoMotionConfig, EgoMotionFilter
from evpose.fusion.motion_predictor import FusionMotionPredictor
from evpose.fusion.polarity import (
    MapPolaritySelector,
    PolarityFilterConfig,
    PolarityPrediction,
    PolarityPredictor,
    classify_events,
    filter_summary,
    observed_point_polarity,
)
from evpose.fusion.state import FusedState


def make_fusion(config: FusionConfig | None = None, calibration=None):
    """The backend ``config.backend`` names, built for ``calibration`` (extrinsic and time offset)."""
    config = config or FusionConfig()
    backend = FusionBackend(config.backend)
    if backend is FusionBackend.FACTOR_GRAPH:
        from evpose.fusion.factor_graph import FactorGraphFusion

        return FactorGraphFusion(config, calibration)
    if backend is FusionBackend.EKF:
        from evpose.fusion.ekf import ErrorStateEkf

        return ErrorStateEkf(config, calibration)
    from evpose.fusion.imu_only import ImuOnlyPropagator

    return ImuOnlyPropagator(config, calibration)


__all__ = [
    "AlignedTimeSurface",
    "EgoMotionConfig",
    "EgoMotionFilter",
    "FusedState",
    "FusionBackend",
    "FusionConfig",
    "FusionMotionPredictor",
    "MapPolaritySelector",
    "PolarityFilterConfig",
    "PolarityPrediction",
    "PolarityPredictor",
    "RegistrationErrorModel",
    "RobustLoss",
    "classify_events",
    "filter_summary",
    "make_fusion",
    "observed_point_polarity",
]
