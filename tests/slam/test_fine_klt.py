"""KLT on MCIs rendered on a finer grid (``FeatureConfig.klt_upsample``)."""

from dataclasses import replace

import numpy as np
import pytest

from evpose.slam.config import FeatureConfig
from evpose.slam.event_image import event_image, fine_coords, sensor_coords, to_uint8
from evpose.slam.features import track_features
from evpose.slam.fine_grid import fine_to_uint8, track_features_fine

W, H = 160, 120
RECTS = [(30, 25, 70, 60), (90, 30, 130, 90), (40, 75, 75, 105)]
CORNERS = np.array([[x, y] for (x0, y0, x1, y1) in RECTS for x in (x0, x1) for y in (y0, y1)], np.float32)


def _edge_events(rng: np.random.Generator, shift: np.ndarray, n_per_edge: int = 500) -> tuple[np.ndarray, np.ndarray]:
    """Events at continuous positions along the rectangles' edges (as warped events land), jittered by 0.25 px."""
    xs, ys = [], []
    for x0, y0, x1, y1 in RECTS:
        for a, b, c, d in [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]:
            s = rng.random(n_per_edge)
            xs.append(a + s * (c - a))
            ys.append(b + s * (d - b))
    x, y = np.concatenate(xs), np.concatenate(ys)
    return x + rng.normal(0, 0.25, len(x)) + shift[0], y + rng.normal(0, 0.25, len(y)) + shift[1]


def test_fine_coords_round_trip_and_splat_centre():
    uv = np.array([[40.25, 30.0], [0.0, 0.0]])
    assert np.allclose(sensor_coords(fine_coords(uv, 2.0), 2.0), uv)
    img = event_image(np.array([40.25]), np.array([30.0]), None, 80, 60, sigma=0.5, scale=2.0)
    assert img.shape == (120, 160)
    ys, xs = np.mgrid[0:120, 0:160]
    centre = np.array([(img * xs).sum(), (img * ys).sum()]) / img.sum()
    assert np.allclose(centre, fine_coords(uv[:1], 2.0)[0], atol=1e-3)
    var_x = (img * (xs - centre[0]) ** 2).sum() / img.sum()
    # The splat's sigma is in sensor pixels: 1 fine pixel (the bilinear vote's share, 0-1/4, depends on the position).
    assert 0.8 < var_x < 1.1


@pytest.mark.parametrize("refine", [False, True])
def test_fine_grid_tracks_subpixel_shifted_edges_more_precisely_than_sensor_grid(refine):
    cfg = FeatureConfig()
    fine = replace(cfg, klt_upsample=2.0, klt_upsample_sigma_px=0.5, klt_upsample_refine=refine)
    e1, e2 = [], []
    for trial in range(8):
        rng = np.random.default_rng(trial)
        shift = rng.uniform(-2.0, 2.0, 2)
        (x0, y0), (x1, y1) = _edge_events(rng, np.zeros(2)), _edge_events(rng, shift)
        a, b = (to_uint8(event_image(x, y, None, W, H, 1.0)) for x, y in ((x0, y0), (x1, y1)))
        n1, ok1 = track_features(a, b, CORNERS, cfg)
        af, bf = (to_uint8(event_image(x, y, None, W, H, 0.5, scale=2.0)) for x, y in ((x0, y0), (x1, y1)))
        n2, ok2 = track_features_fine(af, bf, CORNERS, fine, prev8=a, cur8=b)
        assert ok1.all() and ok2.all()
        e1.append(np.linalg.norm(n1 - CORNERS - shift, axis=1))
        e2.append(np.linalg.norm(n2 - CORNERS - shift, axis=1))
    rms1, rms2 = (float(np.sqrt(np.mean(np.concatenate(e) ** 2))) for e in (e1, e2))
    assert rms2 < 0.85 * rms1, (rms1, rms2)


def test_fine_to_uint8_strided_maximum_matches_the_full_scaling():
    rng = np.random.default_rng(0)
    x0, y0 = _edge_events(rng, np.zeros(2))
    img = event_image(x0, y0, None, W, H, 0.5, scale=2.0)
    assert np.array_equal(fine_to_uint8(img, 0), to_uint8(img))
    fast = fine_to_uint8(img, 2)
    assert fast.dtype == np.uint8 and fast.shape == img.shape
    assert np.abs(fast.astype(int) - to_uint8(img)).max() <= 12
    assert not fine_to_uint8(np.zeros((8, 8), np.float32), 2).any()
    signed = fine_to_uint8(np.array([[-1.0, 0.0], [0.0, 1.0]], np.float32), 1)
    assert signed[0, 1] == 128 and signed[0, 0] < 10 and signed[1, 1] > 250
