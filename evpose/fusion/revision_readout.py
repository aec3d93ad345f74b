"""The real-time pose read out with what the fixed-lag smoother has since learnt about the window's older states.

Option ``FusionConfig.revision_readout_states`` (L, 0 = off) and ``revision_readout_gain`` (g), factor graph only.
When state k is added, each older state k-l of the window (l = 1..L) has two estimates: the one written when it was
the newest (the real-time output at its time) and the smoother's estimate now, which includes the registrations that
came after it. Their difference is that state's *revision*. The read-out adds g times the mean revision of states
k-1..k-L to state k's estimate: positions additively, rotations as a world-frame rotation vector about the camera
centre. Causal: only states and registrations up to k enter.

What it is for (issue 7, 240x180): the registrations carry slow errors (a few edges' event offsets, session 33/34),
which the real-time estimate follows and a smoother, fed later registrations that see other edges, partly takes out
(offline 3.09 mm against 5.26 mm in real time). Re-predicting state k from the smoothed state k-L with the IMU gives
state k's own estimate back (the IMU factors tie the window together: within 0.2 mm, measured open loop), so the
smoother's past holds no more than its present; what the present misses is how much the newer registrations revised
the older states, which is correlated with state k's own slow error. A gain above 1 because a revision is only part
of the error the state carried.

Only the written pose changes: the fusion's state, its IMU propagation (the registrations' prior), the tracker's
internal pose and the recorded fusion inputs are untouched, so tracking is bit for bit the same with it on or off.
Cost: L pose reads from the smoother plus L rotation logs (~0.1 ms per update for L = 7).

Measured (session 36, rt36; open-loop replays of recorded fusion inputs are exact for a read-out; scripts
``/tmp/s36/rt36/revise.py`` and the CLI figures in ``FusionConfig.revision_readout_states``): see that field.
"""

from __future__ import annotations

import numpy as np


def mean_revision(revisions: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Mean (world rotation vector rad (3,), position m (3,)) of per-state revisions."""
    r = np.zeros(3)
    p = np.zeros(3)
    for dr, dp in revisions:
        r += dr
        p += dp
    n = float(len(revisions))
    return r / n, p / n


def revision(gtsam, T_now: np.ndarray, T_then: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One state's revision: (Log(R_now R_then^T) world rad (3,), p_now - p_then m (3,)) of two camera poses (4, 4)."""
    dR = T_now[:3, :3] @ T_then[:3, :3].T
    return np.asarray(gtsam.Rot3.Logmap(gtsam.Rot3(dR)), np.float64), T_now[:3, 3] - T_then[:3, 3]


def revised_pose(gtsam, T_world_cam: np.ndarray, rotation: np.ndarray, position: np.ndarray, gain: float) -> np.ndarray:
    """``T_world_cam`` moved by ``gain`` times a (rotation vector, position) revision: rotation about the camera centre
    in the world frame, position added."""
    out = np.array(T_world_cam, np.float64, copy=True)
    out[:3, :3] = np.asarray(gtsam.Rot3.Expmap(gain * rotation).matrix(), np.float64) @ out[:3, :3]
    out[:3, 3] += gain * position
    return out


def readout_pose(fusion, T_world_cam: np.ndarray) -> np.ndarray | None:
    """The revised camera pose of ``fusion``'s newest state (a :class:`~evpose.fusion.factor_graph.FactorGraphFusion`
    whose ``history`` already holds that state), or None while fewer than ``revision_readout_states`` older states
    are in the window (the start, and after each ``initialize``)."""
    c = fusion.config
    n = int(c.revision_readout_states)
    if n <= 0 or fusion.index < n or len(fusion.history) < n + 1:
        return None
    gtsam = fusion._gtsam
    revs = []
    for lag in range(1, n + 1):
        then = fusion.extrinsic.cam_pose(fusion.history[-1 - lag][1].pose().matrix())
        now = fusion.extrinsic.cam_pose(fusion.smoother.calculateEstimatePose3(fusion._keys(fusion.index - lag)[0]).matrix())
        revs.append(revision(gtsam, now, then))
    rotation, position = mean_revision(revs)
    return revised_pose(gtsam, T_world_cam, rotation, position, float(c.revision_readout_gain))
