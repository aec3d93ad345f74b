"""The visual gyro: the rotation between two event images from their edges."""

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.visual_gyro import VisualGyroConfig, edge_field, ridge_mask, visual_rotation

K = np.array([[247.0, 0.0, 172.5], [0.0, 247.0, 129.5], [0.0, 0.0, 1.0]])
W, H = 346, 260


def _segments(seed: int) -> np.ndarray:
    """Bearings (N, 3) of 40 random straight segments (a scene of edges), z = 1."""
    rng = np.random.default_rng(seed)
    pts = []
    for _ in range(40):
        a = np.r_[rng.uniform(-0.6, 0.6, 2), 1.0]
        d = np.r_[rng.normal(size=2), 0.0]
        pts.append(a + np.linspace(0.0, 0.15, 80)[:, None] * d / np.linalg.norm(d))
    return np.concatenate(pts)


def _image(bearings: np.ndarray, R_cam: np.ndarray) -> np.ndarray:
    """8-bit splat image of ``bearings`` seen by a camera rotated by ``R_cam`` (bilinear votes, 1 px blur)."""
    X = bearings @ R_cam
    u = K[0, 0] * X[:, 0] / X[:, 2] + K[0, 2]
    v = K[1, 1] * X[:, 1] / X[:, 2] + K[1, 2]
    img = np.zeros((H, W), np.float32)
    for x, y in zip(u, v):
        if 0 <= x < W - 1 and 0 <= y < H - 1:
            x0, y0 = int(x), int(y)
            fx, fy = x - x0, y - y0
            img[y0, x0] += (1 - fx) * (1 - fy)
            img[y0, x0 + 1] += fx * (1 - fy)
            img[y0 + 1, x0] += (1 - fx) * fy
            img[y0 + 1, x0 + 1] += fx * fy
    img = cv2.GaussianBlur(img, (5, 5), 1.0)
    return np.clip(255.0 * img / img.max(), 0, 255).astype(np.uint8)


def test_ridge_mask_keeps_only_the_crest_of_a_blurred_line():
    img = np.zeros((20, 30), np.float32)
    img[:, 12] = 1.0
    img = cv2.GaussianBlur(img, (7, 7), 1.0)
    mask = ridge_mask(img, 0.25 * img.max())
    assert mask[:, 12].all() and mask.sum() == 20


def test_visual_rotation_recovers_a_small_camera_rotation():
    B = _segments(3)
    R_true = Rotation.from_rotvec(np.radians([0.3, -0.8, 0.2])).as_matrix()
    prev8, cur8 = _image(B, np.eye(3)), _image(B, R_true)
    R = visual_rotation(prev8, cur8, K, np.eye(3), VisualGyroConfig())
    assert R is not None
    err = np.degrees(np.linalg.norm(Rotation.from_matrix(R_true.T @ R).as_rotvec()))
    assert err < 0.08, err  # from 0.88 deg: about a third of a pixel
    assert visual_rotation(prev8, cur8, K, np.eye(3), VisualGyroConfig()) is not None  # deterministic, repeatable
    np.testing.assert_array_equal(R, visual_rotation(prev8, cur8, K, np.eye(3), VisualGyroConfig()))


def test_visual_rotation_refuses_images_that_do_not_match():
    cfg = VisualGyroConfig()
    prev8 = _image(_segments(3), np.eye(3))
    assert visual_rotation(prev8, np.zeros_like(prev8), K, np.eye(3), cfg) is None
    assert visual_rotation(prev8, _image(_segments(4), np.eye(3)), K, np.eye(3), cfg) is None  # another scene
    assert edge_field(np.zeros_like(prev8), cfg) is None
