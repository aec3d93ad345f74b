"""Line landmarks: ridge segments detected once, 3-D lines triangulated from back-projected planes, tracks matched and
triangulated as the camera moves, and the pose recovered from 1-D distances to the matched lines."""

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam.edge_tracking import EdgeTrackingConfig, solve_pose_across_edges
from evpose.slam.line_landmarks import (LineLandmarkConfig, LineMap, backproject_plane, closest_on_line, detect_segments,
                                        line_measurements, match_segments, project_segment, triangulate_line,
                                        triangulation_angle_deg, update_tracks)

K = np.array([[247.0, 0.0, 172.5], [0.0, 247.0, 129.5], [0.0, 0.0, 1.0]])
W, H = 346, 260
# Vertical 3-D lines (room corners) at different depths, and one horizontal one.
LINES = [np.array([[x, -0.8, z], [x, 0.8, z]]) for x, z in ((-1.0, 3.0), (0.4, 4.0), (1.2, 2.5))]
LINES.append(np.array([[-1.0, 0.9, 3.5], [1.0, 0.9, 3.5]]))


def _pose(yaw_deg: float, t) -> np.ndarray:
    """``T_world_cam``: yawed about the camera's y axis, at ``t``."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("y", yaw_deg, degrees=True).as_matrix()
    T[:3, 3] = t
    return T


def _render(T_wc: np.ndarray) -> np.ndarray:
    """8-bit MCI of thin blurred ridges where the lines project."""
    img = np.zeros((H, W), np.float32)
    T_cw = invert_pose(T_wc)
    for X in LINES:
        p = project_segment(K, T_cw, X)
        if p is not None:
            cv2.line(img, (int(round(p[0] * 16)), int(round(p[1] * 16))), (int(round(p[2] * 16)), int(round(p[3] * 16))), 1.0, 1,
                     cv2.LINE_AA, shift=4)
    img = cv2.GaussianBlur(img, (0, 0), 1.0)
    return (255.0 * img / img.max()).astype(np.uint8)


def test_detect_segments_merges_the_two_flanks_of_a_ridge_into_its_centre():
    img = np.zeros((H, W), np.float32)
    img[20:240, 150] = 1.0
    img8 = (255 * cv2.GaussianBlur(img, (0, 0), 1.0) / cv2.GaussianBlur(img, (0, 0), 1.0).max()).astype(np.uint8)
    segs = detect_segments(img8, LineLandmarkConfig())
    assert len(segs) == 1
    assert abs(0.5 * (segs[0, 0] + segs[0, 2]) - 150.0) < 0.5


def test_triangulate_line_recovers_a_vertical_line_from_translated_views():
    X = LINES[1]
    planes, centres = [], []
    for i in range(4):
        T_wc = _pose(2.0 * i, [0.1 * i, 0.0, 0.0])
        planes.append(backproject_plane(K, T_wc, project_segment(K, invert_pose(T_wc), X)))
        centres.append(T_wc[:3, 3])
    X0, d = triangulate_line(np.array(planes))
    assert abs(abs(d[1]) - 1.0) < 1e-9
    assert np.allclose(X0[[0, 2]], X[0, [0, 2]], atol=1e-9)
    assert triangulation_angle_deg(X0, d, np.array(centres)) > 4.0
    P, depth = closest_on_line(K, T_wc, project_segment(K, invert_pose(T_wc), X)[:2], X0, d)
    assert np.allclose(P, X[0], atol=1e-9) and depth > 0


def test_pure_rotation_triangulates_no_line():
    cfg = LineLandmarkConfig()
    lm = LineMap(0)
    for i in range(8):
        T_wc = _pose(1.5 * i, [0.0, 0.0, 0.0])
        update_tracks(lm, K, T_wc, detect_segments(_render(T_wc), cfg), (H, W), cfg)
    assert max(len(t.planes) for t in lm.tracks) == 8  # tracked all along, but never triangulated
    assert lm.landmarks() == []


def test_match_segments_refuses_an_ambiguous_pair():
    cfg = LineLandmarkConfig()
    pred = [np.array([100.0, 20.0, 100.0, 200.0])]
    assert match_segments(pred, np.array([[103.0, 30.0, 103.0, 190.0]]), cfg) == [0]
    assert match_segments(pred, np.array([[103.0, 30.0, 103.0, 190.0], [96.0, 30.0, 96.0, 190.0]]), cfg) == [-1]
    assert match_segments(pred, np.array([[100.0, 30.0, 180.0, 30.0]]), cfg) == [-1]  # across: not the same line


def test_tracks_triangulate_as_the_camera_translates_and_then_place_a_predicted_pose():
    cfg = LineLandmarkConfig()
    lm = LineMap(0)
    poses = [_pose(1.5 * i, [0.03 * i, 0.0, 0.0]) for i in range(12)]
    for T_wc in poses[:10]:
        update_tracks(lm, K, T_wc, detect_segments(_render(T_wc), cfg), (H, W), cfg)
    found = lm.landmarks()
    assert len(found) >= 3
    for t in found:  # each 3-D line lies on one of the true lines
        err = min(max(float(np.linalg.norm(np.cross(X[1] - X[0], t.X[k] - X[0]))) / float(np.linalg.norm(X[1] - X[0])) for k in range(2))
                  for X in LINES)
        assert err < 0.15  # within 4 % of the depth, from 0.27 of baseline at 2.5-4
    truth = poses[10]
    guess = truth @ np.block([[Rotation.from_euler("y", 0.8, degrees=True).as_matrix(), np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]])
    segs = detect_segments(_render(truth), cfg)
    tracks, Xw, uv, nrm, _ = line_measurements(lm, K, invert_pose(guess), segs, (H, W), cfg)
    assert len(tracks) >= 2  # two vertical lines at different depths: yaw and sideways translation
    res = solve_pose_across_edges(K, Xw, uv, nrm, invert_pose(guess), EdgeTrackingConfig(min_points=4))
    assert res.ok
    R_err = Rotation.from_matrix(res.T_cw[:3, :3] @ truth[:3, :3]).magnitude()
    assert np.degrees(R_err) < 0.3  # the guess's 0.8 deg yaw offset mostly removed
