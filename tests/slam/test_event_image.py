import numpy as np

from evpose.slam.event_image import event_image, local_std_score, to_uint8


def test_event_image_splat_keeps_mass_and_centre():
    img = event_image(np.array([40.25]), np.array([30.0]), None, 80, 60, sigma=1.0)
    assert abs(img.sum() - 1.0) < 1e-4
    ys, xs = np.mgrid[0:60, 0:80]
    assert abs((img * xs).sum() - 40.25) < 1e-3
    assert abs((img * ys).sum() - 30.0) < 1e-3
    var_x = (img * (xs - 40.25) ** 2).sum()
    assert abs(var_x - 1.0) < 0.05  # tent (1/6) + blur = sigma^2


def test_event_image_signed_polarity_cancels():
    img = event_image(np.array([10.0, 10.0]), np.array([10.0, 10.0]), np.array([1, -1]), 20, 20)
    assert np.abs(img).max() < 1e-6


def test_event_image_applies_per_slice_homography():
    H = np.stack([np.eye(3), np.array([[1, 0, 5.0], [0, 1, -2.0], [0, 0, 1]])])
    img = event_image(np.array([10.0]), np.array([10.0]), None, 40, 40, 1.0, np.array([1]), H)
    assert np.unravel_index(np.argmax(img), img.shape) == (8, 15)


def test_local_std_prefers_sharp_over_blurred_image():
    rng = np.random.default_rng(0)
    x, y = rng.uniform(5, 95, 50), rng.uniform(5, 75, 50)
    sharp = event_image(np.repeat(x, 20), np.repeat(y, 20), None, 100, 80)
    smear = np.linspace(0, 6, 20)
    blurred = event_image((x[:, None] + smear).ravel(), np.repeat(y, 20), None, 100, 80)
    assert local_std_score(sharp, 16) > local_std_score(blurred, 16)


def test_to_uint8_handles_empty_and_signed_images():
    assert to_uint8(np.zeros((4, 4), np.float32)).max() == 0
    out = to_uint8(np.array([[-1.0, 0.0, 1.0]], np.float32))
    assert out[0, 0] < out[0, 1] < out[0, 2]
