"""The velocity prior of an inertial local BA window taken from what the previous BA knew about it
(``InertialWindowConfig.velocity_marginal``, off by default).

Session 41 (ba41, ``/tmp/s41/ba41``: ``run.py --dump``, ``dumpba.py``, ``show.py``, ``proj.py``; E-I-C2, main's
defaults, no oracle) dumped the first three local inertial BAs after the IMU initialisation, factor by factor. Indoors
the window is six coasted keyframes 4-6 ms apart with 6-15 reprojections of 2-6 points; its IMU factors are consistent
at the initial values (error 0 but for the new keyframe's, 2-6) and stiff (micrometres over 5 ms), so the window moves
rigidly with the oldest keyframe's velocity; the oldest pose is fixed, its velocity held only by the isotropic
``InertialConfig.ba_velocity_prior_sigma`` (0.5 m/s, as large as the velocity), the points are free: the visual term
has no scale and sets only the direction of the window's translation. The reprojections (error 3-36 at the initial
values, 0.01-11 at the solution) turn the velocity by up to 96 deg in one window (seed 0 57, seed 2 54 then 39, seed 6
81, 96, 36), away from a direction the initialisation had right, and under the isotropic prior the speed ends near its
projection ``|v| cos(angle)``: seed 2 6 deg off the truth's direction before the first local BA, 48 after, 84 after
the second, 1.60 -> 1.07 -> 0.86 m/s (truth 1.24); seed 6 1-2 deg off, 81-89 after, 0.57 -> 0.067 -> 0.046 -> 0.011
m/s, the window's truth metres per map unit 2.2 -> 21 -> 29 -> 211; seed 0 0.40 -> 0.19. Re-solved without the
velocity prior the same graphs go anywhere from 0.01 to 5.6 m/s; without the reprojections they keep the velocities.
Neither the bias (moves < 1e-3 m/s^2), gravity (its error over 30 ms is sub-millimetre), the IMU noise densities
(continuous-time, as gtsam takes them) nor the preintegration over coasted keyframes is at fault. On the landing (seed
0) the windows are visually tracked keyframes 60-150 ms apart with 11-60 reprojections each: the direction stays
within 1-3 deg of the truth, the speed moves +18 / -14 / -9 % per window (truth within 4.0-4.4 m/s).

This carries the velocity's marginal covariance from the BA that last held it instead (an approximation of
marginalising the keyframe that leaves the window: the next window re-uses some of the same observations, which
``velocity_marginal_inflation`` allows for); the direction then holds (seed 2: within 2 deg, 1.60 m/s kept, ATE 13.3
-> 4.5 %), and so does a wrong speed (the indoor initialisations hand over 0.46 of the true speed on seed 6, 1.29 on
seed 2, 0.32 on seed 0).
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
