"""Edge tracking: 1-D across-the-edge measurements of map points and the pose they pin together with a motion prior."""

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.edge_tracking import EdgeTrackingConfig, edge_normal, measure_across_edges, search_across, solve_pose_across_edges
from evpose.slam.geometry import project

K = np.array([[247.0, 0.0, 172.5], [0.0, 247.0, 129.5], [0.0, 0.0, 1.0]])
W, H = 346, 260


def _vertical_lines(xs: list[float]) -> np.ndarray:
    """8-bit image of blurred vertical lines at columns ``xs``."""
    img = np.zeros((H, W), np.float32)
    for x in xs:
        img[:, int(round(x))] = 1.0
    img = cv2.GaussianBlur(img, (7, 7), 1.0)
    return (255.0 * img / img.max()).astype(np.uint8)


def _pose(rotvec_deg, t) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(np.radians(rotvec_deg)).as_matrix()
    T[:3, 3] = t
    return T


def test_edge_normal_of_a_vertical_edge_points_across_it():
    patch = _vertical_lines([172])[120:131, 167:178]
    n, straight = edge_normal(patch)
    assert abs(abs(n[0]) - 1.0) < 1e-3 and abs(n[1]) < 1e-3
    assert straight > 0.95


def test_search_across_finds_the_edge_wherever_the_prediction_sits_along_it():
    img = _vertical_lines([180])
    patch = cv2.getRectSubPix(img, (11, 11), (180.0, 100.0))
    for v in (60.0, 100.0, 170.0):  # along the edge every position looks the same: the search never slides there
        s = search_across(img, patch, np.array([176.0, v]), np.array([1.0, 0.0]), EdgeTrackingConfig())
        assert s is not None and abs(s - 4.0) < 0.2, s


def test_search_across_refuses_a_blank_line_and_a_far_edge():
    img = _vertical_lines([180])
    patch = cv2.getRectSubPix(img, (11, 11), (180.0, 100.0))
    cfg = EdgeTrackingConfig(search_px=8)
    assert search_across(img, patch, np.array([120.0, 100.0]), np.array([1.0, 0.0]), cfg) is None
    assert search_across(img, patch, np.array([191.0, 100.0]), np.array([1.0, 0.0]), cfg) is None  # 11 px away: out of reach


def _scene(seed: int) -> np.ndarray:
    """Points on 8 vertical lines in front of the camera, at 2-4 m, in a band about the optical axis' height (there the
    pitch moves no point across a vertical edge)."""
    rng = np.random.default_rng(seed)
    pts = []
    for x in np.linspace(-1.2, 1.2, 8):
        z = rng.uniform(2.0, 4.0)
        for y in rng.uniform(-0.15, 0.15, 6):
            pts.append([x, y, z])
    return np.array(pts)


def _measure(Xw: np.ndarray, T_true_cw: np.ndarray, T_pred_cw: np.ndarray):
    """Measurements of vertical edges: the true projection's column, at the predicted projection's row."""
    uv_true, _ = project(K, T_true_cw, Xw)
    uv_pred, _ = project(K, T_pred_cw, Xw)
    return np.c_[uv_true[:, 0], uv_pred[:, 1]], np.tile([1.0, 0.0], (len(Xw), 1))


def test_vertical_edges_pin_the_yaw_and_leave_the_pitch_to_the_prior():
    Xw = _scene(1)
    T_true = _pose([0.0, 1.5, 0.0], [0.02, 0.0, 0.0])
    T_pred = _pose([0.4, 0.0, 0.0], [0.0, 0.0, 0.0])  # yaw 1.5 deg off, pitch 0.4 deg off (and invisible)
    uv, nrm = _measure(Xw, T_true, T_pred)
    cfg = EdgeTrackingConfig(sigma_rotation_deg=0.5, sigma_translation_ratio=0.005)
    res = solve_pose_across_edges(K, Xw, uv, nrm, T_pred, cfg)
    assert res.ok, res.reason
    assert res.n_on_edge == len(Xw) and res.info_gain > 100
    rv = Rotation.from_matrix(res.T_cw[:3, :3]).as_rotvec()
    assert abs(np.degrees(rv[1]) - 1.5) < 0.25, np.degrees(rv)  # the edges move the yaw to the truth
    assert abs(np.degrees(rv[0]) - 0.4) < 0.05, np.degrees(rv)  # the pitch stays at the prediction: nothing measures it
    proj, _ = project(K, res.T_cw, Xw)
    assert np.max(np.abs(proj[:, 0] - uv[:, 0])) < 0.5


def test_too_few_measurements_or_no_information_is_no_track():
    Xw = _scene(2)
    T = np.eye(4)
    uv, nrm = _measure(Xw, T, T)
    cfg = EdgeTrackingConfig(min_points=12)
    assert not solve_pose_across_edges(K, Xw[:5], uv[:5], nrm[:5], T, cfg).ok
    loose = EdgeTrackingConfig(sigma_rotation_deg=0.01, sigma_translation_ratio=0.0001, min_info_gain=4.0)
    res = solve_pose_across_edges(K, Xw, uv, nrm, T, loose)  # a prior far tighter than the edges: a coast, not a track
    assert not res.ok and "prior" in res.reason


def test_measure_across_edges_measures_points_on_lines_only():
    img = _vertical_lines([120, 220])
    T = np.eye(4)
    # Two points on the lines, one on blank image; their templates cut where the truth puts them.
    uv_true = np.array([[120.0, 90.0], [220.0, 170.0], [60.0, 130.0]])
    z = 3.0
    Xw = np.c_[(uv_true[:, 0] - K[0, 2]) * z / K[0, 0], (uv_true[:, 1] - K[1, 2]) * z / K[1, 1], np.full(3, z)]
    patches = [cv2.getRectSubPix(img, (11, 11), (float(u), float(v))) for u, v in uv_true]
    T_pred = _pose([0.0, 0.5, 0.0], [0.0, 0.0, 0.0])  # 2 px of yaw off
    idx, uv, nrm = measure_across_edges(img, K, T_pred, Xw, patches, EdgeTrackingConfig())
    assert idx.tolist() == [0, 1]
    np.testing.assert_allclose(uv[:, 0], [120.0, 220.0], atol=0.2)
