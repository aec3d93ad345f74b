"""Refinement of an event-inertial map's IMU initialisation: scale and gravity re-solved once the map is longer.

The first IMU initialisation rests on a few keyframes of an up-to-scale visual
map (``InertialConfig.init_min_span_s``, thinned to ``init_min_gap_s``); on
the simulated landing it left maps up to 1.65 times too large. ORB-SLAM3
refines its initialisation as the map grows; here the same alignment
(:func:`evpose.slam.inertial.initialize_imu`) runs once more over all keyframes
of the now metric map, the map is rescaled and re-aligned with the result, and
an inertial BA over every keyframe follows.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from evpose.core.imu import ImuSamples
from evpose.slam.atlas import SlamMap
from evpose.slam.inertial import ImuInitResult, InertialConfig, initialize_imu
from evpose.slam.inertial_ba import inertial_local_bundle_adjustment


def refine_map_scale(m: SlamMap, K: np.ndarray, imu: ImuSamples, T_cam_imu: np.ndarray, time_offset_us: int, ic: InertialConfig,
                     ba_iterations: int, ba_huber_px: float) -> ImuInitResult:
    """Re-align the IMU-initialised map ``m`` in place (marks it refined); a refused alignment leaves it as it is."""
    m.scale_refined = True
    kfs = m.keyframes
    res = initialize_imu([k.t_us for k in kfs], [k.T_wc for k in kfs], imu, T_cam_imu, time_offset_us,
                         replace(ic, max_residual_ratio=ic.refine_max_residual_ratio, max_motion_residual_ratio=0.0))
    if not res.ok:
        return res
    if ic.refine_min_scale > 0 and res.scale < ic.refine_min_scale:
        # InertialConfig.refine_min_scale: the alignment's bias towards zero, not a correction of a metric map.
        return replace(res, ok=False, reason=f"refined scale {res.scale:.3g} shrinks the map below {ic.refine_min_scale:g} of its size")
    m.transform(res.R_align, res.scale)
    m.scale *= res.scale
    st = m.inertial
    # Velocities live in the map frame and follow the similarity; the alignment's own estimates replace those it solved.
    st.velocities = {k: res.scale * (res.R_align @ v) for k, v in st.velocities.items()}
    st.velocities.update({kfs[k].id: v for k, v in zip(res.used, res.velocities)})
    # InertialWindowConfig.velocity_marginal: the carried covariances follow the similarity too (the BA below renews them).
    st.velocity_cov = {k: res.scale**2 * (res.R_align @ c @ res.R_align.T) for k, c in st.velocity_cov.items()}
    if ic.inertial_ba:
        inertial_local_bundle_adjustment(m, st, K, imu, T_cam_imu, time_offset_us, len(kfs), ba_iterations, ba_huber_px,
                                         ic.acc_noise, ic.gyro_noise, ic.acc_bias_sigma, ic.gyro_bias_sigma, ic.velocity_from_imu,
                                         velocity_prior_sigma=ic.ba_velocity_prior_sigma, min_span_s=ic.ba_min_span_s, span_keyframes=ic.ba_span_keyframes,
                                         marginals=ic.ba_window.velocity_marginal)
    return res
