"""The visual gyro's edge distance field is the exact Euclidean distance, the same on every call (session 37: OpenCV's
DIST_MASK_PRECISE changed in the last bits from call to call, and the written coasts chain the measured rotations)."""

import cv2
import numpy as np

from evpose.slam import SlamConfig
from evpose.slam.visual_gyro import VisualGyroConfig, edge_field, visual_rotation


def _lines_image(seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = np.zeros((180, 240), np.uint8)
    for _ in range(40):
        p0, p1 = rng.integers(0, 180, 2), rng.integers(0, 180, 2)
        cv2.line(img, (int(p0[0] * 4 / 3), int(p0[1])), (int(p1[0] * 4 / 3), int(p1[1])), int(rng.integers(80, 255)), 1)
    return img


def test_the_distance_field_is_the_same_on_every_call_and_exact():
    img, cfg = _lines_image(), VisualGyroConfig()
    fields = [edge_field(img.copy(), cfg) for _ in range(20)]
    for f in fields[1:]:
        for a, b in ((fields[0].dist, f.dist), (fields[0].gx, f.gx), (fields[0].gy, f.gy)):
            np.testing.assert_array_equal(a, b)
    # The field grows with the distance to the nearest edge pixel (a lone one on an otherwise empty image).
    one = np.zeros((40, 40), np.uint8)
    one[20, 20] = 200
    f = edge_field(one, VisualGyroConfig(max_distance_px=50.0))
    assert f is not None and f.dist[20, 20] < f.dist[20, 23] and f.dist[20, 23] < f.dist[20, 30]


def test_the_measured_rotation_is_the_same_on_every_call():
    img = _lines_image()
    img2 = cv2.warpAffine(img, np.float32([[1, 0, 1.5], [0, 1, 0.3]]), (240, 180))
    K = np.array([[200.0, 0, 119.5], [0, 200.0, 89.5], [0, 0, 1]])
    out = [visual_rotation(img.copy(), img2.copy(), K, np.eye(3), VisualGyroConfig()) for _ in range(5)]
    assert out[0] is not None
    for R in out[1:]:
        np.testing.assert_array_equal(R, out[0])
    # A 1.5 px shift at f = 200 px is a turn of about 0.43 deg about the vertical axis.
    angle = np.degrees(np.arccos(np.clip((np.trace(out[0]) - 1) / 2, -1, 1)))
    assert 0.2 < angle < 0.7


def test_written_coasts_are_on_by_default_and_the_online_gyro_is_off():
    vg = SlamConfig().visual_gyro
    assert vg.written_coasts and not vg.enabled and vg.written_coasts_max_map_s == 0.5
