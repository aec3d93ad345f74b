"""Event-only coasts written on the visual gyro while tracking coasts as it always did.

An event-only map that starves coasts on the rotation rate and camera-frame velocity of its own newest poses
(:mod:`evpose.slam.event_coasting`). Indoors nearly every coast ends with the map lost (session 37: of the 7282
coasted poses of indoor seeds 0-53 under session 36's defaults, 7281 lie in a map's last coast; ``/tmp/s37/eo37``), so
the coasted poses feed nothing back into the map and only shape the written trajectory, and their across-track error
is the largest share of the rooms' ATE (session 36: 0.57 of 2.135 points at coasted poses 0.15-0.6 s into a map).
Most of it sits in young maps, one or two PnP poses before a 0.4 s coast (``maps.py``: 0.646 of indoor 0-19's 2.161
points), whose rate comes from a few milliseconds of two-view poses. Oracles (the coast's rate or velocity direction
replaced by the truth's in the camera frame, scratch code, tags ``oW`` / ``oV`` / ``oWV`` / ``oWVnow``, indoor 0-19):
the true rate held -0.183 +- 0.264 points (those young maps 0.646 -> 0.361); the true velocity direction +1.199 +- 0.321
(the map's own orientation is off along the rotation-translation valley, and its velocity is consistent with it, not
with the truth: seed 0's first map moves along -z in its camera frame where the truth moves along -x); both +0.185.

The visual gyro (:mod:`evpose.slam.visual_gyro`) measures the rotation between consecutive MCIs from their edges.
Coasting on it online (``VisualGyroConfig.enabled``) changes the MCIs' warp priors and with them every later map, and
its gain drowns in that chaos (figures there). Here the coast stays as it is and a second, *written* pose is kept for
each coasted MCI of a young map: the same coast model run on the written poses, its orientation the written previous
pose's turned by the measured rotation. :meth:`evpose.slam.atlas.SlamMap.trajectory` writes it in place of the coasted
pose, so tracking, keyframes, points, statuses and tracked time are bit-identical with or without it (all 54 indoor
runs' step logs, landing 0-23's trajectories, E-I-C2 indoor 0 / 11 and landing 0 by trajectory sha), and the indoor
gain, paired, is -0.253 +- 0.057 points over 0-53 (figures: ``VisualGyroConfig.written_coasts``). It is still causal:
each written pose uses only the MCIs up to its own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.atlas import SlamMap
from evpose.slam.event_coasting import camera_frame_rate, event_only_coast_pose


@dataclass
class WrittenPoses:
    """A map's trajectory as it will be written: its times and the written poses (``T_world_cam``, online frame), each
    coasted pose with a written alternative replaced by it; what the coast model reads its motion from."""

    traj_t: list[int]
    traj_T: list[np.ndarray]


def written_poses(m: SlamMap) -> WrittenPoses:
    alt = m.traj_alt
    return WrittenPoses(m.traj_t, [alt[t][0] if t in alt else T for t, T in zip(m.traj_t, m.traj_T)])


def written_coast_pose(m: SlamMap, t_us: int, span_us: int, young_span_us: int, measure) -> np.ndarray | None:
    """The written pose of the coasted MCI at ``t_us``: the event-only coast (rate and camera-frame velocity over the
    newest ``span_us`` of written poses, or over all of them when the map is younger and they span at least
    ``young_span_us``) with its orientation replaced by the written previous pose's turned by ``measure(dR0)``, the
    rotation measured since the previous MCI started from ``dR0`` (None: the coast's own rotation is kept). None
    when the written poses give no motion (the caller then writes the coasted pose)."""
    w = written_poses(m)
    T = event_only_coast_pose(w, t_us, span_us)
    if T is None and young_span_us > 0 and w.traj_t and w.traj_t[-1] - w.traj_t[0] >= young_span_us:
        T = event_only_coast_pose(w, t_us, w.traj_t[-1] - w.traj_t[0])
    if T is None:
        return None
    rate = camera_frame_rate(w, span_us)  # as the online visual gyro starts its search (identity for a young map)
    dR0 = np.eye(3) if rate is None else Rotation.from_rotvec(rate * (t_us - w.traj_t[-1])).as_matrix()
    dR = measure(dR0)
    if dR is not None:
        T = T.copy()
        T[:3, :3] = w.traj_T[-1][:3, :3] @ dR
    return T
