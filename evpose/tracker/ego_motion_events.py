"""The ego-motion event filter's step in the tracker: which of this step's noise-filtered events it keeps.

A 5 ms batch is too short for the ego-motion consistency test, so each batch is judged together with the last
``history_us`` of kept events (ideal pixel coordinates and times), which this module carries from step to step.
"""

from __future__ import annotations

import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.core.events import EventArray
from evpose.tracker.modes import MotionComponents

EgoHistory = tuple[np.ndarray, np.ndarray, np.ndarray]
"""Recent noise-filtered events as (ideal x px, ideal y px, t us int64) arrays."""


def empty_ego_history() -> EgoHistory:
    return (np.empty(0), np.empty(0), np.empty(0, np.int64))


def ego_motion_keep(components: MotionComponents, calibration: CameraCalibration, points_world: np.ndarray,
                    history: EgoHistory, events: EventArray, keep: np.ndarray, until: int) -> tuple[np.ndarray, EgoHistory]:
    """Keep-mask of the ego-motion filter over this step's events (only noise-filtered ones are judged), and the
    event history to judge the next step's events against."""
    state = components.motion.fusion.predict(until)
    omega = np.zeros(3) if state.omega_cam is None else state.omega_cam
    x = events.x.astype(np.float64)
    y = events.y.astype(np.float64)
    if calibration.dist:
        xy = calibration.undistortion_table[events.y, events.x].astype(np.float64)
        x, y = xy[:, 0], xy[:, 1]
    out = np.ones(len(events), bool)
    idx = np.flatnonzero(keep)
    ego = components.ego_motion
    hx, hy, ht = history
    # A 5 ms batch is too short for the consistency test: judge it against the last history_us of events too.
    horizon = int(ego.config.history_us)
    first = int(np.searchsorted(ht, until - horizon, side="left")) if horizon > 0 else ht.size
    hx, hy, ht = hx[first:], hy[first:], ht[first:]
    ax = np.concatenate([hx, x[idx]])
    ay = np.concatenate([hy, y[idx]])
    at = np.concatenate([ht, events.t[idx].astype(np.int64)])
    if idx.size:
        out[idx] = ego.filter(
            ax, ay, at, state.T_world_cam, omega, state.velocity_world, calibration.K,
            calibration.width, calibration.height, points_world=points_world, t_ref_us=until, n_context=ht.size,
        )
    return out, ((ax, ay, at) if horizon > 0 else history)
