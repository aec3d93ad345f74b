"""TDF: ~0 on the newest events, gradients at query points, box computation equals the full image."""

import numpy as np

from evpose.core.events import EventArray
from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField, decay_lut
from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig

W, H = 80, 60


def edge_surface(eta_ms=10.0):
    """A vertical edge that swept from column 20 to 40, one column per ms, ending at t = 20 ms."""
    ts = SeparatedTimeSurface(TimeSurfaceConfig(eta_ms=eta_ms), W, H)
    t, x, y = [], [], []
    for k in range(21):
        t += [k * 1_000] * 40
        x += [20 + k] * 40
        y += list(range(10, 50))
    ts.update(EventArray.from_arrays(t, x, y, [1] * len(t)))
    return ts


def test_tdf_is_zero_on_the_newest_events_without_blur():
    ts = edge_surface()
    f = TemporalDistanceField(DistanceFieldConfig(blur_px=0), W, H)
    f.compute(ts, 20_000)
    img = f.image(0)
    assert np.all(img[10:50, 40] < 1e-3)
    assert np.all(img[:, 60] == 1.0)  # never fired
    # Rises behind the edge following 1 - exp(-dt/eta).
    assert np.isclose(img[30, 30], 1 - np.exp(-1.0), atol=1e-3)


def test_blurred_tdf_keeps_its_minimum_on_the_edge_rows():
    ts = edge_surface()
    f = TemporalDistanceField(DistanceFieldConfig(blur_px=5), W, H)
    f.compute(ts, 20_000)
    img = f.image(0)
    row = img[30]
    assert np.argmin(row) in (38, 39, 40)
    assert row[45] > row[40]


def test_decay_table_matches_the_exponential():
    eta_us = 7_300.0
    table, shift = decay_lut(eta_us)
    dt = np.arange(0, 12 * 7_300, 37)
    approx = table[np.minimum((dt + ((1 << shift) >> 1)) >> shift, table.size - 1)]
    assert np.max(np.abs(approx - (1 - np.exp(-dt / eta_us)))) < 1e-3


def test_sampled_gradient_matches_finite_differences_of_the_field():
    ts = edge_surface()
    f = TemporalDistanceField(DistanceFieldConfig(blur_px=5), W, H)
    f.compute(ts, 20_000)
    uv = np.array([[35.0, 30.0], [41.0, 25.0], [30.0, 40.0]])
    _, grad, inside = f.sample(uv)
    assert inside.all()
    img = f.image(0).astype(np.float64)
    for (u, v), g in zip(uv.astype(int), grad):
        assert np.isclose(g[0], (img[v, u + 1] - img[v, u - 1]) / 2, atol=1e-6)
        assert np.isclose(g[1], (img[v + 1, u] - img[v - 1, u]) / 2, atol=1e-6)


def test_sampling_outside_the_image_reports_no_evidence():
    ts = edge_surface()
    f = TemporalDistanceField(DistanceFieldConfig(), W, H)
    f.compute(ts, 20_000)
    val, grad, inside = f.sample(np.array([[-1.0, 5.0], [W - 0.5, 5.0], [5.0, np.nan]]))
    assert not inside.any() and np.all(val == 1.0) and np.all(grad == 0.0)


def test_field_in_a_padded_box_equals_the_full_field_inside_it():
    ts = edge_surface()
    full = TemporalDistanceField(DistanceFieldConfig(blur_px=5), W, H)
    full.compute(ts, 20_000)
    box = TemporalDistanceField(DistanceFieldConfig(blur_px=5), W, H)
    box.compute(ts, 20_000, roi=(5, 55, 10, 60))
    inner = (slice(9, 51), slice(14, 56))  # the box minus the blur radius + gradient stencil
    assert np.allclose(box.value[0][inner], full.value[0][inner], atol=1e-6)
    assert np.allclose(box.grad_u[0][inner], full.grad_u[0][inner], atol=1e-6)
    assert np.all(box.image(0)[:, :10] == 1.0)
    val, grad, inside = box.sample(np.array([[5.0, 30.0], [30.0, 30.0]]))
    assert inside.tolist() == [False, True] and val[0] == 1.0 and np.all(grad[0] == 0.0)


def test_recomputing_with_a_smaller_box_clears_the_previous_one():
    ts = edge_surface()
    f = TemporalDistanceField(DistanceFieldConfig(), W, H)
    f.compute(ts, 20_000)
    f.compute(ts, 20_000, roi=(0, 5, 0, 5))
    assert np.all(f.image(0)[10:50, 40] == 1.0)
    assert not f.sample(np.array([[40.0, 30.0]]))[2][0]


def test_per_polarity_fields_are_computed_on_request():
    ts = edge_surface()
    f = TemporalDistanceField(DistanceFieldConfig(blur_px=0), W, H)
    f.compute(ts, 20_000, polarities=(1, -1))
    assert f.slots_ready == (1, 2)
    assert f.image(1)[30, 40] < 1e-3
    assert np.all(f.image(-1) == 1.0)  # no OFF events
    val, _, _ = f.sample(np.array([[40.0, 30.0], [40.0, 30.0]]), polarity=np.array([1, -1]))
    assert val[0] < 1e-3 and val[1] == 1.0


def test_curvature_images_are_second_differences_of_the_field():
    ts = edge_surface()
    f = TemporalDistanceField(DistanceFieldConfig(blur_px=5), W, H)
    f.compute(ts, 20_000, curvature=True)
    img = f.image(0).astype(np.float64)
    r, c = 30, 39
    assert np.isclose(f.hess[0, 0, r, c], img[r, c + 1] - 2 * img[r, c] + img[r, c - 1], atol=1e-6)
    assert np.isclose(f.hess[2, 0, r, c], img[r + 1, c] - 2 * img[r, c] + img[r - 1, c], atol=1e-6)
    cross = (img[r + 1, c + 1] - img[r + 1, c - 1] - img[r - 1, c + 1] + img[r - 1, c - 1]) / 4
    assert np.isclose(f.hess[1, 0, r, c], cross, atol=1e-6)
    assert f.hess[0, 0, r, 40] > 0  # the field's valley along the edge is convex across it


def _subpixel_argmin(row):
    i = int(np.argmin(row))
    a, b, c = (float(v) for v in row[i - 1 : i + 2])
    return i + 0.5 * (a - c) / (a - 2 * b + c)


def test_blurred_minimum_trails_a_moving_edge_more_with_a_wider_blur():
    # The field is one-sided (a ramp behind the edge, 1 ahead of it), so a blur pulls its
    # minimum back along the motion: the lag registration compensates with ``field_lag_ms``.
    ts = edge_surface()
    lags = []
    for blur in (3, 5):
        f = TemporalDistanceField(DistanceFieldConfig(blur_px=blur), W, H)
        f.compute(ts, 20_000)
        lags.append(40.0 - _subpixel_argmin(f.image(0)[30]))
    assert 0.2 < lags[0] < lags[1] < 2.0, lags


def test_derivative_kernel_matches_replicated_border_differences_on_any_box_shape():
    from evpose.frontend.distance_field import field_derivatives

    rng = np.random.default_rng(3)
    for h, w in [(2, 2), (2, 7), (9, 3), (17, 31)]:
        img = rng.random((h, w)).astype(np.float32)
        outs = [np.full((h + 4, w + 6), 7.0, np.float32) for _ in range(5)]
        field_derivatives(img, 1, 2, True, *outs)
        p = np.pad(img, 1, mode="edge")
        c, lf, rt, up, dn = p[1:-1, 1:-1], p[1:-1, :-2], p[1:-1, 2:], p[:-2, 1:-1], p[2:, 1:-1]
        d = np.float64
        # Same arithmetic as the kernel: differences in float32, "x - 2 f0 + y" in float64.
        want = [0.5 * (rt - lf), 0.5 * (dn - up), rt.astype(d) - 2.0 * c.astype(d) + lf.astype(d),
                0.25 * (p[2:, 2:] - p[2:, :-2] - p[:-2, 2:] + p[:-2, :-2]), dn.astype(d) - 2.0 * c.astype(d) + up.astype(d)]
        for got, ref in zip(outs, want):
            assert np.array_equal(got[1 : 1 + h, 2 : 2 + w], ref.astype(np.float32))
            assert np.all(got[0] == 7.0) and np.all(got[:, :2] == 7.0)  # nothing written outside the box


def test_pixels_older_than_the_decay_table_read_exactly_one_and_younger_ones_the_exponential():
    # Timestamps straddling the table's last bin (12 eta): the skip for old pixels must agree with the lookup.
    eta_ms = 10.0
    ts = SeparatedTimeSurface(TimeSurfaceConfig(eta_ms=eta_ms), W, H)
    t_query = 200_000
    table, shift = decay_lut(eta_ms * 1e3)
    edge = ((table.size - 1) << shift) - ((1 << shift) >> 1)  # smallest age that lands in the last bin
    ages = np.array([0, 1, 5_000, 10_000, edge - 17, edge - 1, edge, edge + 1, edge + 500, t_query - 1])
    x = np.arange(ages.size) * 3
    order = np.argsort(-ages)  # events must arrive in time order
    ts.update(EventArray.from_arrays((t_query - ages)[order], x[order], np.full(ages.size, 7)[order], np.ones(ages.size)[order]))
    f = TemporalDistanceField(DistanceFieldConfig(blur_px=0), W, H)
    f.compute(ts, t_query)
    got = f.image(0)[7, x]
    expected = table[np.minimum((ages + ((1 << shift) >> 1)) >> shift, table.size - 1)]
    assert np.array_equal(got, expected)
    assert np.all(got[ages >= edge] == 1.0) and np.all(got[ages < edge] < 1.0)
    assert np.max(np.abs(got - (1 - np.exp(-ages / (eta_ms * 1e3))))) < 1e-3


def test_curvature_from_the_field_values_equals_the_curvature_images_bit_for_bit():
    from evpose.frontend.distance_field import bilinear_curvature_from_value, bilinear_sample_curvature

    ts = edge_surface()
    rng = np.random.default_rng(2)
    for box in ((0, H, 0, W), (12, 47, 25, 61), (5, 7, 30, 33)):
        f = TemporalDistanceField(DistanceFieldConfig(blur_px=3), W, H)
        f.compute(ts, 20_000, (0,), box, curvature=True)
        r0, r1, c0, c1 = box
        # Random points inside the box, its corners and edges (replicated borders).
        u = np.concatenate([rng.uniform(c0, c1 - 1, 300), [c0, c1 - 1, c0, c1 - 1, c0 + 0.5]])
        v = np.concatenate([rng.uniform(r0, r1 - 1, 300), [r0, r0, r1 - 1, r1 - 1, r1 - 1.0]])
        for uu, vv in zip(u, v):
            a = bilinear_sample_curvature(f.hess, f.box, 0, uu, vv)
            b = bilinear_curvature_from_value(f.value, f.box, 0, uu, vv)
            assert a == b, (box, uu, vv, a, b)
