import numpy as np

from evpose.slam.affine_refine import AffineTracks, align_template, blurred, cut_template, homography_jacobians
from evpose.slam.config import FeatureConfig


def _corner_image(A: np.ndarray, corner: np.ndarray, shape=(120, 160)) -> np.ndarray:
    """A smooth bright square with a dimmer tab, its corner at ``corner``, warped by ``A`` (template offsets -> image offsets)."""
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]].astype(np.float64)
    d = np.stack([xx - corner[0], yy - corner[1]], -1) @ np.linalg.inv(A).T

    def step(z):
        return 1.0 / (1.0 + np.exp(-z / 0.6))

    img = step(d[..., 0]) * step(d[..., 1]) * step(12 - d[..., 0]) * step(12 - d[..., 1])
    img += 0.5 * step(d[..., 0] + 6) * step(-d[..., 0]) * step(d[..., 1] - 3) * step(8 - d[..., 1])
    return (200 * img).astype(np.float32)


def _rotated_sheared(angle_deg: float, scale: float, shear: float) -> np.ndarray:
    a = np.radians(angle_deg)
    return scale * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]) @ np.array([[1.0, shear], [0.0, 1.0]])


def test_align_template_recovers_an_affine_warped_corner_within_0_2_px():
    c0 = np.array([60.3, 50.6])
    tpl = cut_template(blurred(_corner_image(np.eye(2), c0), 1.0), c0, 15)
    A = _rotated_sheared(12.0, 1.15, 0.08)
    c1 = np.array([83.7, 61.2])
    img = blurred(_corner_image(A, c1), 1.0)
    for start in ([1.2, -0.8], [-1.5, 1.0], [0.0, 1.8]):
        centre, linear, cc = align_template(tpl, img, c1 + start, np.eye(2), 5)
        assert np.hypot(*(centre - c1)) < 0.2
        assert cc > 0.99
        assert np.abs(linear - A).max() < 0.1


def test_align_template_refuses_a_search_region_outside_the_image():
    c0 = np.array([60.3, 50.6])
    img = blurred(_corner_image(np.eye(2), c0), 1.0)
    tpl = cut_template(img, c0, 15)
    assert align_template(tpl, img, np.array([3.0, 50.0]), np.eye(2), 5) is None
    assert cut_template(img, np.array([2.0, 50.0]), 15) is None


def test_homography_jacobians_match_finite_differences():
    H = np.array([[1.05, 0.02, 3.0], [-0.03, 0.97, -2.0], [1e-4, -2e-4, 1.0]])
    uv = np.array([[10.0, 20.0], [150.0, 90.0]])

    def apply(p):
        q = H @ np.array([p[0], p[1], 1.0])
        return q[:2] / q[2]

    J = homography_jacobians(H, uv)
    eps = 1e-4
    for k, p in enumerate(uv):
        num = np.stack([(apply(p + [eps, 0]) - apply(p - [eps, 0])) / (2 * eps),
                        (apply(p + [0, eps]) - apply(p - [0, eps])) / (2 * eps)], axis=1)
        assert np.allclose(J[k], num, atol=1e-6)


def test_refine_moves_a_track_onto_its_birth_patch_and_keeps_refused_ones():
    cfg = FeatureConfig(affine_refine=True)
    c0 = np.array([60.3, 50.6])
    prev = blurred(_corner_image(np.eye(2), c0), cfg.affine_blur_px)
    tracks = AffineTracks()
    ids = np.array([7, 8])
    p0 = np.array([c0, [100.0, 100.0]], np.float32)  # track 8 sits on a flat patch
    tracks.adopt(ids, p0, prev, cfg)
    A = _rotated_sheared(8.0, 1.1, 0.0)
    c1 = np.array([64.6, 53.1])
    img = blurred(_corner_image(A, c1), cfg.affine_blur_px)
    klt = np.array([c1 + [0.9, -0.6], [101.0, 100.5]], np.float32)
    out = tracks.refine(ids, p0, klt, np.array([True, True]), prev, img, cfg)
    assert np.hypot(*(out[0] - c1)) < 0.2
    assert np.array_equal(out[1], klt[1])
    tracks.prune(np.array([7]))
    assert set(tracks.templates) == {7}
