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

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import SlamMap
from evpose.slam.coasting import camera_frame_velocity, coast_pose
from evpose.slam.event_coasting import camera_frame_rate, event_only_coast_pose
from evpose.slam.geometry import project


@dataclass
class WrittenPoses:
    """A map's trajectory as it will be written: its times and the written poses (``T_world_cam``, online frame), each
    coasted pose with a written alternative replaced by it; what the coast model reads its motion from."""

    traj_t: list[int]
    traj_T: list[np.ndarray]


def written_poses(m: SlamMap) -> WrittenPoses:
    alt = m.traj_alt
    return WrittenPoses(m.traj_t, [alt[t][0] if t in alt else T for t, T in zip(m.traj_t, m.traj_T)])


def _long_velocity_coast_pose(w: WrittenPoses, t_us: int, span_us: int, velocity_span_us: int) -> np.ndarray | None:
    """:func:`event_only_coast_pose` over the written poses with the camera-frame velocity read over the newest
    ``velocity_span_us`` instead of ``span_us`` (over the whole trajectory when it is shorter, if it spans ``span_us``)."""
    rate = camera_frame_rate(w, span_us)
    if rate is None:
        return None
    v = camera_frame_velocity(w, min(velocity_span_us, w.traj_t[-1] - w.traj_t[0]))
    if v is None:
        return None
    R_wc = w.traj_T[-1][:3, :3] @ Rotation.from_rotvec(rate * (t_us - w.traj_t[-1])).as_matrix()
    return coast_pose(w, t_us, R_wc, v)


def written_coast_pose(m: SlamMap, t_us: int, span_us: int, young_span_us: int, measure, parallax_depth=None,
                       velocity_span_us: int = 0, velocity_span_by_gap: bool = False) -> np.ndarray | None:
    """The written pose of the coasted MCI at ``t_us``: the event-only coast (rate and camera-frame velocity over the
    newest ``span_us`` of written poses, or over all of them when the map is younger and they span at least
    ``young_span_us``) with its orientation replaced by the written previous pose's turned by ``measure(dR0)``, the
    rotation measured since the previous MCI started from ``dR0`` (None: the coast's own rotation is kept). None
    when the written poses give no motion (the caller then writes the coasted pose). ``parallax_depth``: a function of
    a ``T_world_cam`` giving the depth of the scene it sees (None: unknown); with it the measured rotation is taken as
    the camera's rotation plus the image motion its translation makes at that depth from the newest written pose
    (:func:`parallax_rotation`), which is removed."""
    w = written_poses(m)
    if velocity_span_by_gap and w.traj_t:
        # Read the velocity over about as long as it is to be extrapolated (a blank's 0.15-0.3 s), not longer.
        velocity_span_us = min(velocity_span_us, max(span_us, t_us - w.traj_t[-1]))
    T = event_only_coast_pose(w, t_us, span_us) if velocity_span_us <= span_us else _long_velocity_coast_pose(w, t_us, span_us, velocity_span_us)
    if T is None and young_span_us > 0 and w.traj_t and w.traj_t[-1] - w.traj_t[0] >= young_span_us:
        T = event_only_coast_pose(w, t_us, w.traj_t[-1] - w.traj_t[0])
    if T is None:
        return None
    rate = camera_frame_rate(w, span_us)  # as the online visual gyro starts its search (identity for a young map)
    dR0 = np.eye(3) if rate is None else Rotation.from_rotvec(rate * (t_us - w.traj_t[-1])).as_matrix()
    dR = measure(dR0)
    if dR is not None and parallax_depth is not None:
        dR = _without_parallax(w, dR, t_us - w.traj_t[-1], span_us, young_span_us, parallax_depth)
    if dR is not None:
        T = T.copy()
        T[:3, :3] = w.traj_T[-1][:3, :3] @ dR
    return T


def parallax_rotation(v_cam: np.ndarray, depth: float, dt: float) -> np.ndarray:
    """Rotation vector (camera frame, rad) a pure-rotation fit reads from the image motion that the camera's translation
    ``v_cam * dt`` (camera frame) makes at the image centre for points at ``depth`` (same units as ``v_cam * dt``).

    A point ahead at depth Z moves, relative to a camera translating by ``v`` and turning by ``w``, by ``-v - w x (0, 0,
    Z)``: its image motion at the centre is that of the rotation ``w + z x v / Z``. The visual gyro fits the rotation
    alone, so on a camera moving across its view it reads ``z x v / Z`` too; the rooms' camera circles sideways at ~1.2
    m/s before walls ~2-3 m away, about 25-35 deg/s on a true 20-100 deg/s turn."""
    return np.cross((0.0, 0.0, 1.0), v_cam) * dt / depth


def _without_parallax(w: WrittenPoses, dR: np.ndarray, dt: float, span_us: int, young_span_us: int, depth_of) -> np.ndarray:
    """``dR`` (measured since the newest written pose, over ``dt`` us) less :func:`parallax_rotation` of the written
    poses' camera-frame velocity (over ``span_us``, or the whole trajectory when shorter and at least ``young_span_us``)
    at ``depth_of(newest written pose)``; ``dR`` itself without either."""
    v = camera_frame_velocity(w, span_us)
    if v is None and young_span_us > 0 and w.traj_t and w.traj_t[-1] - w.traj_t[0] >= young_span_us:
        v = camera_frame_velocity(w, w.traj_t[-1] - w.traj_t[0])
    z = depth_of(w.traj_T[-1]) if v is not None else None
    if z is None or not z > 0:
        return dR
    rv, p = Rotation.from_matrix(dR).as_rotvec(), parallax_rotation(v, z, dt)
    if not (rv @ p > 0 and np.linalg.norm(p) < np.linalg.norm(rv)):
        # The parallax a young map's velocity predicts against or beyond the measured turn: that velocity is what is
        # wrong (indoor 8's second map holds one 110-140 deg off the truth's), so the measurement is kept as it is.
        return dR
    return Rotation.from_rotvec(rv - p).as_matrix()


def depth_in_view(m: SlamMap, K: np.ndarray, shape: tuple[int, int], min_points: int = 5):
    """A ``parallax_depth`` for :func:`written_coast_pose`: the median depth of the map's points that project into an
    image of ``shape`` (rows, columns) from the pose, None with fewer than ``min_points`` of them."""
    X = m.point_array()

    def depth(T_wc: np.ndarray) -> float | None:
        if len(X) < min_points:
            return None
        uv, z = project(K, invert_pose(T_wc), X)
        inside = (z > 1e-9) & (uv[:, 0] >= 0) & (uv[:, 0] < shape[1]) & (uv[:, 1] >= 0) & (uv[:, 1] < shape[0])
        return float(np.median(z[inside])) if inside.sum() >= min_points else None

    return depth
