"""The fusion's positive-definiteness test of registration covariances: Cholesky's verdict, without warnings."""

import warnings

import numpy as np

from evpose.fusion.config import FusionConfig
from evpose.fusion.factor_graph import _positive_definite, registration_covariance


def _cholesky_succeeds(c):
    try:
        np.linalg.cholesky(c)
        return True
    except np.linalg.LinAlgError:
        return False


def test_positive_definite_agrees_with_numpys_cholesky_and_warns_about_nothing():
    rng = np.random.default_rng(0)
    cases = [np.eye(6), -np.eye(6), np.ones((6, 6)), np.zeros((6, 6)), np.diag([1.0, 1, 1, 1, 1, -1e-12])]
    for _ in range(30):
        M = rng.normal(size=(6, 6))
        cases.append(0.5 * (M + M.T))  # mostly indefinite
        cases.append(M @ M.T * 1e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for c in cases:
            assert _positive_definite(c) == _cholesky_succeeds(c)


def test_an_indefinite_registration_covariance_falls_back_to_the_default_sigmas():
    cfg = FusionConfig()
    bad = np.diag([1e-4] * 5 + [-1e-4])
    sr, st = cfg.registration_default_sigma_rot, cfg.registration_default_sigma_trans
    expected = np.diag([sr * sr] * 3 + [st * st] * 3) + np.eye(6) * cfg.registration_min_sigma ** 2
    assert np.array_equal(registration_covariance(cfg, bad), expected)
