"""Guards of the event-inertial SLAM against maps that start wrong: a two-view start whose rotation the gyro
contradicts (``InertialConfig.init_max_gyro_deg``), and a map lost young (``InertialConfig.discard_lost_young_s``).

Why (E-I-C2 indoors, main e1abba0, ``/tmp/s36/ei36/steperr.py``): the SLAM paper's RPE is per step, so one wrong step
can fail a 3 m recording. Seed 30's rotation RPE (0.031 deg/m) is 84 % one step, the first map's two-view
start (a homography of "13.6 deg parallax" 13.3 deg off the true rotation); seed 3's (0.0151 deg/m) 84 % one step,
a two-view map re-joined onto the lost one 8.8 deg off. Over 0.1-0.2 s the gyro's rotation is good to hundredths of
a degree even with an unknown bias (the simulated part's is at most 0.004 rad/s).

And the RPE is the mean over the atlas's maps of each map's error per metre it travelled, so a 2 cm map weighs as
much as the 3 m one after it: the first two-view map of seeds 11, 22 and 24 was lost 17-28 ms after it started, with
3-4 poses (seed 11: 10 deg of rotation error per step), and those seeds failed both targets (4.48 m/m and 208 deg/m,
0.163 / 0.079, 0.225 / 0.056) while their long map met them. ORB-SLAM3's tracking resets the active map when it is lost
with fewer than 10 keyframes (``KeyFramesInMap() < 10``) instead of keeping it in the atlas; here a keyframe comes
every few milliseconds indoors, so the test is on the map's age. A discarded map
keeps its id and place in the atlas (step results refer to maps by id) but loses its keyframes, points and poses, so
no trajectory is written for it.
"""

from __future__ import annotations

import numpy as np

from evpose.slam.atlas import SlamMap
from evpose.slam.gyro_prior import rotation_angle_deg


def two_view_gyro_disagreement_deg(R_c0_c1: np.ndarray, gyro_c0_c1: np.ndarray | None) -> float:
    """Angle between a two-view start's relative camera rotation ``R_c0_c1`` (camera 1's orientation in camera 0's
    frame) and the gyro's over the same interval, degrees (0 without a gyro rotation)."""
    if gyro_c0_c1 is None:
        return 0.0
    return rotation_angle_deg(np.asarray(gyro_c0_c1, np.float64), np.asarray(R_c0_c1, np.float64))


def young_lost_map(m: SlamMap | None, max_span_s: float) -> bool:
    """Whether ``m``, being lost, is to be discarded: not IMU-initialised and its poses span less than ``max_span_s``
    (0: never)."""
    if m is None or max_span_s <= 0 or m.imu_initialised or not m.traj_t:
        return False
    return (m.traj_t[-1] - m.traj_t[0]) / 1e6 < max_span_s


def discard_map(m: SlamMap, reason: str) -> None:
    """Empty ``m`` in place (keyframes, points, poses and their observations); its id stays taken."""
    m.keyframes.clear()
    m.points.clear()
    m.traj_t.clear()
    m.traj_T.clear()
    m.traj_ref.clear()
    m.traj_rel.clear()
    m.traj_obs.clear()
    m.lost_reason = f"discarded while young: {reason}"


def bundle_keyframes(m: SlamMap, candidates: list, window: int) -> list:
    """The keyframes of ``candidates`` the visual local BA over the newest ``window`` keyframes holds as variables
    (:func:`evpose.slam.bundle_adjustment.local_bundle_adjustment`: those observing a point that has two observations
    and is seen from the window), in order (``InertialConfig.ba_gyro_prior_chain``)."""
    in_window = {kf.id for kf in m.keyframes[-window:]} if window > 0 else set()
    used: set[int] = set()
    for p in m.points.values():
        if len(p.obs) >= 2 and any(k in in_window for k in p.obs):
            used.update(p.obs)
    return [kf for kf in candidates if kf.id in used]


def anchored_window(m: SlamMap, window: int) -> int:
    """``window`` trimmed so that its oldest keyframe, the one the visual local BA holds fixed, is one the BA holds at all
    (:func:`bundle_keyframes`); unchanged when none is (``InertialConfig.ba_gyro_prior_chain``). A coasted keyframe
    that sees no point is left out of the BA: fixing it anchored nothing, the window turned freely, and the poses
    between it and the next keyframe took the turn as one step (indoor seed 6, 8.8 deg)."""
    kfs = m.keyframes[-window:] if window > 0 else []
    used = {kf.id for kf in bundle_keyframes(m, kfs, window)}
    for i, kf in enumerate(kfs):
        if kf.id in used:
            return window - i
    return window


def starts_at_rejoin(m: SlamMap, window: int) -> bool:
    """Whether the visual local BA's window of the newest ``window`` keyframes starts at the first keyframe of a
    re-joined segment (:mod:`evpose.slam.map_rejoin`), whose first two keyframes the coasting placed and scaled
    (``InertialConfig.rejoin_scale_anchor``)."""
    return m.segment_start_kf > 0 and 2 <= window <= len(m.keyframes) and m.keyframes[-window].id == m.segment_start_kf
