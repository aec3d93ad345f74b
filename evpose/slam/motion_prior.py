"""Constant-velocity and constant-rotation-rate priors between consecutive keyframes of the event-only local BA.

Monocular keyframes of a camera at several metres from its scene are a few decimetres apart, and a tilt error of one
degree is a sideways shift of about ten centimetres there: the baseline, and with it the depth of every point
triangulated from it, is wrong by tens of percent. The map scale then jumps from one keyframe to the next (on the
simulated landing, 0.5 s pieces of one map aligned on their own needed scales 45-260 % apart), which no image factor
sees. A camera carried by a vehicle does not change its velocity by that much between keyframes tens of milliseconds
apart; this factor says so, with a sigma relative to the speed (the scale is unknown) and a Huber kernel so that real
accelerations still pass. It is off by default: on 24 landing seeds it did not lower the ATE as a whole (the figures
are in ``TrackingConfig.ba_velocity_prior``). The rotation-rate factor says the same of the keyframes' rotation (no
scale to normalise there); it removed a rotation collapse at the simulated landing's corner but not the scale drift
that sets the ATE, and is off too (``TrackingConfig.ba_rotation_rate_prior_deg_s``).
"""

from __future__ import annotations

import numpy as np


def velocity_residual(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray, dt0: float, dt1: float) -> np.ndarray:
    """Change of velocity from ``p0 -> p1`` (``dt0`` s) to ``p1 -> p2`` (``dt1`` s), map units per second (3,)."""
    return (p2 - p1) / dt1 - (p1 - p0) / dt0


def keyframe_triples(kfs: list, present: set, free: set, max_gap_s: float):
    """Consecutive keyframe triples ``(a, b, c, dt0, dt1)`` of ``kfs`` that a motion factor may join: all three in
    ``present``, one at least in ``free``, both gaps (seconds) positive and at most ``max_gap_s`` (the motion over a
    longer gap is not one velocity or rotation rate)."""
    for a, b, c in zip(kfs[:-2], kfs[1:-1], kfs[2:]):
        ids = {a.id, b.id, c.id}
        if not ids <= present or not ids & free:
            continue
        dt0, dt1 = (b.t_us - a.t_us) / 1e6, (c.t_us - b.t_us) / 1e6
        if 0 < dt0 <= max_gap_s and 0 < dt1 <= max_gap_s:
            yield a, b, c, dt0, dt1


def add_velocity_factors(graph, kfs: list, present: set, free: set, sigma_ratio: float, max_gap_s: float = 0.5) -> int:
    """Add one constant-velocity factor per triple of consecutive keyframes of ``kfs`` (all in ``present``, the graph's
    pose variables, one at least in ``free``); returns how many.

    Each factor's sigma is ``sigma_ratio`` times the triple's mean speed before the optimisation, map units per second.
    Triples with a gap over ``max_gap_s`` seconds are skipped (the motion over it is not one velocity).
    """
    import gtsam
    from gtsam.symbol_shorthand import X

    n = 0
    for a, b, c, dt0, dt1 in keyframe_triples(kfs, present, free, max_gap_s):
        p0, p1, p2 = (k.T_wc[:3, 3] for k in (a, b, c))
        speed = 0.5 * (np.linalg.norm(p1 - p0) / dt0 + np.linalg.norm(p2 - p1) / dt1)
        if not speed > 0:
            continue
        noise = gtsam.noiseModel.Robust.Create(gtsam.noiseModel.mEstimator.Huber.Create(2.0),
                                               gtsam.noiseModel.Isotropic.Sigma(3, sigma_ratio * speed))
        graph.add(gtsam.CustomFactor(noise, [X(a.id), X(b.id), X(c.id)], _error(dt0, dt1)))
        n += 1
    return n


def _error(dt0: float, dt1: float):
    w = (1.0 / dt0, -1.0 / dt1 - 1.0 / dt0, 1.0 / dt1)

    def error(this, values, jacobians):
        poses = [values.atPose3(k) for k in this.keys()]
        p = [np.asarray(P.translation(), np.float64) for P in poses]
        if jacobians is not None:
            # d translation / d (rotation, translation) of a Pose3 perturbed on the right: [0, R].
            for i, P in enumerate(poses):
                J = np.zeros((3, 6))
                J[:, 3:] = w[i] * P.rotation().matrix()
                jacobians[i] = J
        return velocity_residual(p[0], p[1], p[2], dt0, dt1)

    return error


def rotation_rate_residual(R0: np.ndarray, R1: np.ndarray, R2: np.ndarray, dt0: float, dt1: float) -> np.ndarray:
    """Change of the body-frame rotation rate from ``R0 -> R1`` (``dt0`` s) to ``R1 -> R2`` (``dt1`` s), rad/s (3,)."""
    from scipy.spatial.transform import Rotation

    r01 = Rotation.from_matrix(R0.T @ R1).as_rotvec()
    r12 = Rotation.from_matrix(R1.T @ R2).as_rotvec()
    return r12 / dt1 - r01 / dt0


def add_rotation_rate_factors(graph, kfs: list, present: set, free: set, sigma_rad_s: float, max_gap_s: float = 0.5) -> int:
    """Add one constant-rotation-rate factor per triple of consecutive keyframes of ``kfs`` (all in ``present``, one at
    least in ``free``); returns how many. The residual is :func:`rotation_rate_residual`, ``sigma_rad_s`` its sigma
    (rad/s) under a Huber kernel at two sigmas. Unlike the velocity, a rotation rate has no monocular scale."""
    import gtsam
    from gtsam.symbol_shorthand import X

    noise = gtsam.noiseModel.Robust.Create(gtsam.noiseModel.mEstimator.Huber.Create(2.0),
                                           gtsam.noiseModel.Isotropic.Sigma(3, sigma_rad_s))
    n = 0
    for a, b, c, dt0, dt1 in keyframe_triples(kfs, present, free, max_gap_s):
        graph.add(gtsam.CustomFactor(noise, [X(a.id), X(b.id), X(c.id)], _rate_error(dt0, dt1)))
        n += 1
    return n


def _jr_inv(phi: np.ndarray) -> np.ndarray:
    """Inverse right Jacobian of SO(3) to first order (keyframe rotations are a few degrees apart)."""
    x, y, z = phi
    return np.eye(3) + 0.5 * np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _rate_error(dt0: float, dt1: float):
    def error(this, values, jacobians):
        R = [values.atPose3(k).rotation().matrix() for k in this.keys()]
        D01, D12 = R[0].T @ R[1], R[1].T @ R[2]
        res = rotation_rate_residual(R[0], R[1], R[2], dt0, dt1)
        if jacobians is not None:
            # Right perturbations R_i Exp(d_i): Log(D01) moves by Jr^-1 (d_1 - D01^T d_0), Log(D12) likewise.
            from scipy.spatial.transform import Rotation

            J01 = _jr_inv(Rotation.from_matrix(D01).as_rotvec())
            J12 = _jr_inv(Rotation.from_matrix(D12).as_rotvec())
            blocks = (J01 @ D01.T / dt0, -J01 / dt0 - J12 @ D12.T / dt1, J12 / dt1)
            for i, B in enumerate(blocks):
                J = np.zeros((3, 6))
                J[:, :3] = B
                jacobians[i] = J
        return res

    return error
