"""The velocity prior of an inertial local BA window taken from what the previous BA knew about it
(``InertialWindowConfig.velocity_marginal``, off by default).

The indoor windows (six keyframes 4-6 ms apart) carry no scale of their own: their IMU factors are stiff over 30 ms
and their few points (1-7 observed per window on coasted keyframes) are free, so the only thing holding the window's
velocity, hence its scale, is the prior on its oldest keyframe's velocity, isotropic at
``InertialConfig.ba_velocity_prior_sigma`` (0.5 m/s, as large as the velocity itself). The visual term constrains only
the direction of the window's translation; given a few points it turns the velocity by 40-57 deg in one window, away
from a direction the initialisation had right (indoor seed 2: 6 deg off the truth's before the first local BA, 48 deg
after, 84 deg after the second), and under an isotropic prior the magnitude then ends near its projection
``|v| cos(angle)``: 1.60 -> 1.07 -> 0.86 m/s (truth 1.24), seed 0 0.40 -> 0.19. This carries the velocity's marginal
covariance from the BA that last held it instead (an approximation of marginalising the keyframe that leaves the
window: the next window re-uses some of the same observations, which ``velocity_marginal_inflation`` allows for).
"""

from __future__ import annotations

import numpy as np


def carried_velocity_noise(cov: np.ndarray, anchors, max_sigma: float):
    """Gaussian noise model of the carried prior: ``velocity_marginal_inflation`` times ``cov`` plus the floor
    ``velocity_marginal_min_sigma`` squared, its eigenvalues capped at ``max_sigma`` squared (never looser than the
    fixed prior it replaces)."""
    import gtsam

    c = anchors.velocity_marginal_inflation * np.asarray(cov, np.float64)
    c = 0.5 * (c + c.T)
    w, U = np.linalg.eigh(c)
    w = np.clip(w + anchors.velocity_marginal_min_sigma**2, anchors.velocity_marginal_min_sigma**2 or 1e-12, max_sigma**2)
    return gtsam.noiseModel.Gaussian.Covariance((U * w) @ U.T)


MARGINAL_KEYFRAMES = 16
"""Newest keyframes of a BA whose velocity marginals are kept: the ones a later window can start at (a full BA's older
keyframes never will)."""


def store_velocity_covariances(graph, result, ids: list, state, scale: float = 1.0) -> None:
    """Marginal covariances of the velocities of keyframes ``ids`` in the solved ``graph`` into ``state.velocity_cov``
    (times ``scale`` squared when the result was rescaled); where they are not finite the entries are dropped, so those
    keyframes fall back to the fixed prior."""
    ids = ids[-MARGINAL_KEYFRAMES:]
    covs = velocity_marginals(graph, result, ids)
    for k in ids:
        c = covs.get(k)
        if c is not None and np.all(np.isfinite(c)):
            state.velocity_cov[k] = scale * scale * c
        else:
            state.velocity_cov.pop(k, None)


POINT_SIGMA = 100.0
"""Sigma of the weak prior each point gets for the marginals only, map units (metres): it settles the depth of a point
that two views a few millimetres apart leave undetermined and does nothing to a point seen at all."""


def velocity_marginals(graph, result, ids: list) -> dict:
    """Keyframe id -> marginal covariance (3, 3) of its velocity ``V(id)`` at the solution ``result`` of ``graph``.

    gtsam's ``Marginals`` refuses the whole graph when one point seen twice over a few millimetres of baseline leaves its
    depth undetermined (every full BA after an indoor initialisation), which says nothing about the velocities: each
    point gets a weak prior (``POINT_SIGMA``) first."""
    import gtsam
    from gtsam.symbol_shorthand import V

    g = gtsam.NonlinearFactorGraph(graph)
    weak = gtsam.noiseModel.Isotropic.Sigma(3, POINT_SIGMA)
    for key in result.keys():
        if chr(gtsam.Symbol(key).chr()) == "l":
            g.add(gtsam.PriorFactorPoint3(key, result.atPoint3(key), weak))
    try:
        marg = gtsam.Marginals(g, result)
        return {k: np.asarray(marg.marginalCovariance(V(k)), np.float64) for k in ids}
    except RuntimeError:
        return {}
