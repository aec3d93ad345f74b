"""The numba forms of the event image's 8-bit scaling and sharpness score equal the numpy code they replaced, bit for bit."""
import numpy as np
import pytest

from evpose.slam.event_image import event_image, local_std_score, robust_maximum, to_uint8
from evpose.slam.fine_grid import fine_to_uint8


def _robust_maximum_ref(magnitudes):
    nz = magnitudes[magnitudes > 0]
    if nz.size == 0:
        return None
    top = float(np.percentile(nz, 99.5))
    return top if top > 0 else float(nz.max())


def _to_uint8_ref(img):
    img = np.asarray(img, dtype=np.float32)
    signed = bool((img < 0).any())
    top = _robust_maximum_ref(np.abs(img))
    if top is None:
        return np.zeros(img.shape, np.uint8)
    if signed:
        out = 128.0 + 127.0 * np.clip(img / top, -1.0, 1.0)
    else:
        out = 255.0 * np.clip(img / top, 0.0, 1.0)
    return out.astype(np.uint8)


def _local_std_score_ref(img, patch):
    img = np.asarray(img, dtype=np.float64)
    h = (img.shape[0] // patch) * patch
    w = (img.shape[1] // patch) * patch
    if h == 0 or w == 0:
        return float(img.std())
    blocks = img[:h, :w].reshape(h // patch, patch, w // patch, patch)
    return float(blocks.std(axis=(1, 3)).mean())


def _random_image(rng, h, w, dtype=np.float32, signed=False):
    img = rng.random((h, w)) * rng.choice([1e-3, 1.0, 1e3]) * (rng.random((h, w)) < rng.uniform(0.0, 1.0))
    if signed:
        img *= rng.choice([-1.0, 1.0], size=(h, w))
    return img.astype(dtype)


def _event_mci(rng, w=346, h=260, n=12000):
    return event_image(rng.uniform(0, w, n), rng.uniform(0, h, n), None, w, h, 1.0)


def test_robust_maximum_equals_numpy_percentile():
    rng = np.random.default_rng(0)
    for i in range(300):
        n = int(rng.integers(1, 3000)) if i % 3 else int(rng.integers(1, 12))
        m = np.abs(_random_image(rng, 1, n, rng.choice([np.float32, np.float64]))).ravel()
        assert robust_maximum(m) == _robust_maximum_ref(m)
    assert robust_maximum(np.zeros(10, np.float32)) is None


def test_robust_maximum_strided_equals_numpy_on_the_strided_image():
    rng = np.random.default_rng(1)
    for _ in range(100):
        img = _random_image(rng, int(rng.integers(2, 120)), int(rng.integers(2, 160)), signed=bool(rng.random() < 0.3))
        stride = int(rng.integers(1, 4))
        assert robust_maximum(img, stride) == _robust_maximum_ref(np.abs(img[::stride, ::stride]))


@pytest.mark.parametrize("signed", [False, True])
def test_to_uint8_equals_numpy_form(signed):
    rng = np.random.default_rng(2 + signed)
    for _ in range(60):
        img = _random_image(rng, int(rng.integers(1, 100)), int(rng.integers(1, 140)), signed=signed)
        np.testing.assert_array_equal(to_uint8(img), _to_uint8_ref(img))
    img = _event_mci(rng)
    np.testing.assert_array_equal(to_uint8(img), _to_uint8_ref(img))
    np.testing.assert_array_equal(to_uint8(np.zeros((5, 7), np.float32)), _to_uint8_ref(np.zeros((5, 7), np.float32)))


def test_to_uint8_with_nan_takes_numpy_form():
    img = np.ones((4, 4), np.float32)
    img[1, 2] = np.nan
    with np.errstate(invalid="ignore"):
        np.testing.assert_array_equal(to_uint8(img), _to_uint8_ref(img))


def test_fine_to_uint8_matches_strided_numpy_maximum():
    rng = np.random.default_rng(4)
    img = event_image(rng.uniform(0, 346, 12000), rng.uniform(0, 260, 12000), None, 346, 260, 0.5, scale=2.0)
    top = _robust_maximum_ref(np.abs(img[::2, ::2]))
    import cv2
    np.testing.assert_array_equal(fine_to_uint8(img, 2), cv2.convertScaleAbs(img, alpha=255.0 / top))


def test_local_std_score_equals_numpy_blocks():
    rng = np.random.default_rng(5)
    for _ in range(400):
        patch = int(rng.choice([4, 6, 8, 9, 12, 16, 24, 32, 48, 64]))
        img = _random_image(rng, int(rng.integers(1, 6 * patch)), int(rng.integers(1, 6 * patch)), rng.choice([np.float32, np.float64]),
                            signed=bool(rng.random() < 0.3))
        assert local_std_score(img, patch) == _local_std_score_ref(img, patch)
    img = _event_mci(rng)
    assert local_std_score(img, 16) == _local_std_score_ref(img, 16)
