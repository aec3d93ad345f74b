"""Exports: TUM trajectory readable by the project's reader, config, PNG and GIF files."""

import numpy as np

from app.export import write_config, write_gif, write_png, write_tum
from app.config_gui import load_config_file
from evpose.io.tum import read_tum
from evpose.tracker.config import TrackerConfig


def test_trajectory_export_round_trips_through_the_tum_reader(tmp_path, bar_recording):
    gt = bar_recording.ground_truth
    path = write_tum(gt, tmp_path / "traj.txt")
    back = read_tum(path)
    assert np.array_equal(back.t, gt.t)
    assert np.allclose(back.position, gt.position, atol=1e-6)


def test_config_png_and_gif_exports(tmp_path):
    import imageio.v3 as iio

    cfg = TrackerConfig(rate_hz=300.0)
    assert load_config_file(TrackerConfig, write_config(cfg, tmp_path / "c.yaml")) == cfg
    img = np.zeros((20, 30, 3), np.uint8)
    img[5:10, 5:10] = 255
    assert np.array_equal(iio.imread(write_png(img, tmp_path / "s.png")), img)
    gif = iio.imread(write_gif([img, 255 - img, img], tmp_path / "v.gif"), index=None)
    assert gif.shape[0] == 3


def test_a_transparent_render_is_exported_over_the_views_background_not_black(tmp_path):
    import imageio.v3 as iio

    from app.export import BACKGROUND_DARK

    rgba = np.zeros((4, 6, 4), np.uint8)  # what the browser's PNG render gives where nothing is drawn
    rgba[1, 1] = (200, 0, 0, 255)  # a drawn pixel stays as drawn
    rgba[2, 2] = (0, 0, 255, 128)  # half covered: blended
    light = iio.imread(write_png(rgba, tmp_path / "light.png"))
    assert light.shape == (4, 6, 3) and (light[0, 0] == 255).all() and tuple(light[1, 1]) == (200, 0, 0)
    assert tuple(light[2, 2]) == (127, 127, 255)
    dark = iio.imread(write_png(rgba, tmp_path / "dark.png", BACKGROUND_DARK))
    assert tuple(dark[0, 0]) == BACKGROUND_DARK
