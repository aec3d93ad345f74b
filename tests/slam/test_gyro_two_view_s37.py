"""Two-view start with the gyro's rotation (:mod:`evpose.slam.gyro_two_view`, ``InertialConfig.init_gyro_two_view``):
the known-rotation solver recovers the translation direction, and a start the gyro contradicts is resolved, not refused."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import evpose.slam.system_initialisation as si
from evpose.slam.config import InitializationConfig
from evpose.slam.gyro_two_view import refine_with_gyro_prior, sampson_px2, translation_direction_ransac, two_view_with_rotation
from evpose.slam.initialization import TwoViewResult
from evpose.slam.step_result import SlamStatus
from tests.slam.test_inertial_guards_s36 import _MapMade, _rz, _Starting

K = np.array([[200.0, 0.0, 120.0], [0.0, 200.0, 90.0], [0.0, 0.0, 1.0]])


def _scene(noise_px: float, outliers: int = 0, baseline=(0.05, 0.01, 0.02), seed: int = 1):
    """Matches of 100 points 2-4 m away seen from the origin and from a camera at ``baseline`` turned by ``R_wc2``."""
    rng = np.random.default_rng(seed)
    X = np.c_[rng.uniform(-1.5, 1.5, (100, 2)), rng.uniform(2.0, 4.0, 100)]
    R_wc2 = Rotation.from_rotvec([0.01, -0.03, 0.02]).as_matrix()
    c2 = np.asarray(baseline, np.float64)

    def proj(Xc):
        return Xc[:, :2] / Xc[:, 2:] * 200.0 + [120.0, 90.0]

    p1 = proj(X) + rng.normal(0.0, noise_px, (100, 2))
    p2 = proj((X - c2) @ R_wc2) + rng.normal(0.0, noise_px, (100, 2))
    p2[:outliers] += rng.uniform(15.0, 30.0, (outliers, 2)) * rng.choice([-1.0, 1.0], (outliers, 2))
    t_true = -R_wc2.T @ c2  # x2 = R x1 + t with R = R_wc2^T
    return p1, p2, R_wc2, t_true / np.linalg.norm(t_true), c2


def _angle_deg(a, b) -> float:
    return float(np.degrees(np.arccos(min(1.0, abs(a @ b) / np.linalg.norm(a) / np.linalg.norm(b)))))


def test_the_known_rotation_solver_recovers_the_translation_direction_exactly_without_noise():
    p1, p2, R_wc2, t_true, _ = _scene(0.0)
    t, inl = translation_direction_ransac(K, p1, p2, R_wc2.T, 1.0)
    assert _angle_deg(t, t_true) < 1e-6
    assert inl.all()


def test_the_known_rotation_solver_rejects_outliers_and_stays_near_the_direction_with_noise():
    p1, p2, R_wc2, t_true, _ = _scene(0.3, outliers=10)
    t, inl = translation_direction_ransac(K, p1, p2, R_wc2.T, 1.0)
    assert not inl[:10].any()  # the ten moved matches
    assert inl[10:].mean() > 0.8
    assert _angle_deg(t, t_true) < 5.0
    assert np.median(sampson_px2(K, R_wc2.T, t, p1[inl], p2[inl])) < 0.3


def test_the_refinement_pulls_a_wrong_rotation_back_only_as_far_as_its_prior_lets_it():
    p1, p2, R_wc2, t_true, _ = _scene(0.1)
    R_true = R_wc2.T
    R_off = Rotation.from_rotvec([0.0, 0.0, np.radians(0.5)]).as_matrix() @ R_true
    t, inl = translation_direction_ransac(K, p1, p2, R_off, 3.0)

    def err(R):
        return float(np.degrees(Rotation.from_matrix(R @ R_true.T).magnitude()))

    R_loose, t_loose = refine_with_gyro_prior(K, p1[inl], p2[inl], R_off, t, 1.0, np.radians(5.0))
    R_tight, _ = refine_with_gyro_prior(K, p1[inl], p2[inl], R_off, t, 1.0, np.radians(1e-4))
    assert err(R_loose) < 0.2 < err(R_tight)
    assert err(R_tight) == pytest.approx(0.5, abs=0.01)
    assert _angle_deg(t_loose, t_true) < 5.0
    assert abs(np.linalg.norm(t_loose) - 1.0) < 1e-12


def test_a_gyro_start_takes_the_gyro_rotation_and_puts_the_second_camera_along_the_baseline():
    p1, p2, R_wc2, _, c2 = _scene(0.2)
    res = two_view_with_rotation(K, p1, p2, R_wc2, InitializationConfig(min_triangulated=12), sigma_deg=0.01, min_parallax_deg=0.3)
    assert res.ok and res.model == "gyro"
    assert float(np.degrees(Rotation.from_matrix(res.T_wc2[:3, :3] @ R_wc2.T).magnitude())) < 0.05
    assert _angle_deg(res.T_wc2[:3, 3], c2) < 5.0 and res.T_wc2[:3, 3] @ c2 > 0  # cheirality picked the sign
    assert np.nanmedian(res.points[res.good, 2]) == pytest.approx(1.0)  # unit median depth, as the decomposition's


def test_a_gyro_start_without_parallax_is_refused_with_its_reason():
    p1, p2, R_wc2, _, _ = _scene(0.05, baseline=(0.004, 0.0, 0.0))
    res = two_view_with_rotation(K, p1, p2, R_wc2, InitializationConfig(min_triangulated=12), min_parallax_deg=0.3)
    assert not res.ok and "median parallax" in res.reason


class _Resolving(_Starting):
    def __init__(self, gyro_on: bool):
        super().__init__(5.0, 1.0)
        self.cfg.inertial.init_gyro_two_view = gyro_on

        def new_map():
            raise _MapMade

        self.atlas = SimpleNamespace(active=None, new_map=new_map)


def _outcome(s: _Resolving) -> str:
    try:
        status, reason, _ = s._try_initialise(SimpleNamespace(t_us=20000, image8=None))
    except _MapMade:
        return "map"
    assert status is SlamStatus.NOT_INITIALISED
    return reason


def test_a_start_far_off_the_gyro_is_resolved_with_the_gyro_instead_of_refused(monkeypatch):
    T = np.eye(4)
    T[:3, :3] = _rz(12.0)
    monkeypatch.setattr(si, "initialize_two_view", lambda *a, **k: TwoViewResult(True, T_wc2=T, model="homography"))
    asked = []

    def solved(K, p1, p2, R, cfg, seed, sigma, model, min_parallax_deg, max_direction_std_deg):
        asked.append((two_view_gyro_deg(R), model, min_parallax_deg, max_direction_std_deg))
        G = np.eye(4)
        G[:3, :3] = R
        return TwoViewResult(True, T_wc2=G, model=model)

    def two_view_gyro_deg(R):
        return float(np.degrees(Rotation.from_matrix(R).magnitude()))

    monkeypatch.setattr(si, "two_view_with_rotation", solved)
    assert "11.0 deg off the gyro" in _outcome(_Resolving(False))  # off: refused as before, the solver never asked
    assert asked == []
    assert _outcome(_Resolving(True)) == "map"
    assert asked[0][0] == pytest.approx(1.0) and asked[0][1].startswith("homography+gyro 11.0 deg") and asked[0][2] == 0.4
    assert asked[0][3] == 0.0  # InertialConfig.init_gyro_two_view_max_direction_std_deg: off

    # A start the gyro's rotation cannot triangulate goes on to the guard with the decomposition's rotation (the
    # default); with init_gyro_two_view_refuse_unsolved it is refused for that.
    monkeypatch.setattr(si, "two_view_with_rotation", lambda *a, **k: TwoViewResult(False, "median parallax 0.1 deg < 0.3"))
    assert "11.0 deg off the gyro" in _outcome(_Resolving(True))
    strict = _Resolving(True)
    strict.cfg.inertial.init_gyro_two_view_refuse_unsolved = True
    assert "median parallax 0.1 deg" in _outcome(strict)
    T[:3, :3] = _rz(2.0)  # 1 deg off: within the guard
    assert _outcome(_Resolving(True)) == "map"
    assert "median parallax" in _outcome(strict)
