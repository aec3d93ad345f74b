"""Image panels: colour maps, reprojected points drawn on the TDF, kept vs removed events."""

import numpy as np

from app.engine import EventsOnlyEngine
from app.frame import Frame
from app.panels import OverlayColour, events_image, panel_images, tdf_image
from evpose.core.events import EventArray


def _frame(uv, residuals, weights, pol):
    z = np.zeros((48, 64), np.float32)
    return Frame(0, 0, z, z, np.ones_like(z), EventArray.empty(), EventArray.empty(),
                 projected_uv=np.asarray(uv, np.float32), residuals=np.asarray(residuals, np.float32),
                 weights=np.asarray(weights, np.float32), predicted_polarity=np.asarray(pol, np.int8))


def test_tdf_overlay_colours_points_by_residual_weight_or_polarity():
    f = _frame([[10, 10], [40, 30]], [0.0, 1.0], [1.0, 0.0], [1, -1])
    s = tdf_image(f).shape[1] // 64
    px = lambda img, u, v: img[v * s + s // 2, u * s + s // 2]  # noqa: E731  (centre of the upscaled pixel)
    by_res = tdf_image(f, OverlayColour.RESIDUAL)
    assert tuple(px(by_res, 10, 10)) == (0, 255, 40) and tuple(px(by_res, 40, 30)) == (255, 0, 40)  # on-edge green, far red
    by_w = tdf_image(f, OverlayColour.WEIGHT)
    assert tuple(px(by_w, 10, 10)) == (0, 255, 40) and tuple(px(by_w, 40, 30)) == (255, 0, 40)
    by_p = tdf_image(f, OverlayColour.POLARITY)
    assert tuple(px(by_p, 10, 10)) == (230, 40, 40) and tuple(px(by_p, 40, 30)) == (40, 90, 230)


def test_events_image_separates_kept_polarities_from_removed():
    kept = EventArray.from_arrays([1, 2], [1, 2], [1, 1], [1, -1])
    removed = EventArray.from_arrays([3], [5], [5], [1])
    img = events_image(kept, removed, 8, 8)
    s = img.shape[1] // 8
    assert tuple(img[1 * s, 1 * s]) == (235, 60, 50)
    assert tuple(img[1 * s, 2 * s]) == (60, 120, 245)
    assert tuple(img[5 * s, 5 * s]) == (110, 110, 110)
    assert img[0, 0].sum() == 0


def test_panel_images_of_a_live_frame_are_rgb_and_show_the_edge(bar_recording):
    eng = EventsOnlyEngine(bar_recording)
    for _ in range(20):
        frame = eng.step()
    imgs = panel_images(frame)
    assert set(imgs) == {"SP-TS positive", "SP-TS negative", "TDF + map points", "events kept / removed"}
    for img in imgs.values():
        assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    assert imgs["SP-TS positive"].max() > 200 and imgs["events kept / removed"].max() > 200
