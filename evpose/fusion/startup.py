"""What the fusion does differently in a track's first moments (both backends): the gyroscope-bias hold
(``FusionConfig.gyro_bias_hold_s``) and the registration covariance widened along its shift / tilt ridges
(``FusionConfig.registration_startup_s``, ``registration_ridge_scale``)."""

from __future__ import annotations

import numpy as np

from evpose.fusion.config import FusionConfig
from evpose.fusion.preintegration import make_preintegration_params
from evpose.core.lapack_calls import eigh


def initial_gyro_bias_sigma(config: FusionConfig) -> float:
    """Prior sigma on the initial gyroscope bias, rad/s: ``gyro_bias_hold_sigma`` while ``gyro_bias_hold_s`` holds it."""
    return float(config.gyro_bias_hold_sigma if config.gyro_bias_hold_s > 0 else config.init_sigma_gyro_bias)


def gyro_bias_release_due(config: FusionConfig, t0_us: int | None, t_us: int) -> bool:
    """Whether a state at ``t_us`` ends the gyroscope-bias hold of a fusion started at ``t0_us`` (None: released)."""
    return t0_us is not None and t_us - t0_us >= config.gyro_bias_hold_s * 1e6


def gyro_bias_release_params(config: FusionConfig, dt_s: float):
    """Preintegration parameters of the one step that releases the held gyroscope bias: its random-walk density
    raised so that the step adds ``init_sigma_gyro_bias**2`` to the bias variance (gtsam integrates the density
    times each piece's duration), everything else as :func:`make_preintegration_params`."""
    p = make_preintegration_params(config)
    density2 = config.gyro_bias_random_walk**2 + config.init_sigma_gyro_bias**2 / max(float(dt_s), 1e-6)
    p.setBiasOmegaCovariance(np.eye(3) * density2)
    return p


STARTUP_RIDGE_DIRECTIONS = 2
"""How many least-constrained directions ``FusionConfig.registration_startup_inflation`` widens: the two largest
eigenvalues of the registration covariance's correlation matrix, for the two ridges where a shift across the optical
axis and a tilt about the perpendicular axis move the image alike (x / tilt about y, y / tilt about x). On the 240x180
landing (seed 0, every update, ``/tmp/s33/gyro33/eig.py``) those two stand out (median eigenvalues 0.01 / 0.03 / 0.37
/ 0.78 / 1.90 / 2.89; the 5th never below 0.87, the 4th never above 1.13) and span both pairs, mixed between them
(and with some height and roll about the optical axis). An uncorrelated covariance has no ridge: its two widened
directions are then whichever the eigen-solver returns first (deterministic, not meaningful)."""


def in_startup(config: FusionConfig, start_us: int | None, t_us: int) -> bool:
    """Whether ``t_us`` lies within ``registration_startup_s`` of a fusion started at ``start_us`` (False before any
    start): the registrations are widened then, and the read-out's depth ratio waits."""
    return start_us is not None and t_us - start_us < config.registration_startup_s * 1e6


def startup_inflated(config: FusionConfig, start_us: int | None, t_us: int, covariance_6x6):
    """The registration covariance at ``t_us`` of a fusion started at ``start_us``, its correlation matrix's
    ``registration_startup_directions`` (:data:`STARTUP_RIDGE_DIRECTIONS` by default) largest eigenvalues times ``registration_startup_inflation`` within
    ``registration_startup_s`` of the start and times ``registration_ridge_scale`` after it (unit-free: the
    eigen-decomposition of the correlation matrix, scaled back by the standard deviations); as given when the factor
    is 1, before any start or when unusable."""
    if start_us is None or covariance_6x6 is None:
        return covariance_6x6
    startup = in_startup(config, start_us, t_us)
    factor = float(config.registration_startup_inflation if startup else config.registration_ridge_scale)
    if factor == 1.0:
        return covariance_6x6
    c = np.asarray(covariance_6x6, np.float64).reshape(6, 6)
    c = 0.5 * (c + c.T)
    # Methods and numpy's own expressions instead of the np.diag / np.all / np.outer / np.linalg.eigh wrappers: the
    # same operations on the same values (every update of a track's first ``registration_startup_s`` runs this).
    diag = c.diagonal()
    if not (np.isfinite(c).all() and (diag > 0).all()):
        return covariance_6x6  # registration_covariance's fallback handles it
    d = np.sqrt(diag)
    dd = d[:, None] * d[None, :]
    w, V = eigh(c / dd)
    w[-int(config.registration_startup_directions):] *= factor
    return ((V * w) @ V.T) * dd
