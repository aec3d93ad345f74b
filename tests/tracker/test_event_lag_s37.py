"""Speed-proportional event leads (session 37, :mod:`evpose.tracker.event_lag`): an event's lead falls by its
polarity's lag times how much its edge's normal image speed exceeds the reference speed; off by default."""

import numpy as np

from evpose.tracker.config import TrackerConfig
from evpose.tracker.event_lag import EventLagConfig, lead_terms
from evpose.tracker.event_registration_kernels import _linearise_events

FX = 200.0
CAMERA = np.array([0.0, 0.0, 3.0])
"""3 m above the map point, looking down."""


def residual(polarity: int, offset_px: float, burst: np.ndarray, speed_m_s: float = 3.0) -> float:
    # One straight edge (along y through the origin) moving +x in the image at FX * speed / 3 px/s (200 px/s at
    # 3 m/s); one event `offset_px` ahead of it (negative: behind), no class lead. Returns its residual, pixels.
    pts = np.array([[0.0, 0.0, 0.0]])
    tg = np.array([[0.0, 1.0, 0.0]])
    R_cw = np.diag([1.0, -1.0, -1.0])  # camera z down
    t_cw = -R_cw @ CAMERA
    twist = np.array([0.0, 0.0, 0.0, -speed_m_s, 0.0, 0.0])  # camera moving -x: the edge moves +x in the image
    ex, ey = np.array([100.0 + offset_px]), np.array([100.0])
    et, ep = np.array([1000], np.int64), np.array([polarity], np.int8)
    assoc, eg = np.array([0], np.int64), np.array([2 ** 62], np.int64)
    H, b, sw, swr = np.zeros((6, 6)), np.zeros(6), np.empty(1), np.empty(1)
    _linearise_events(1, ex, ey, et, ep, assoc, pts, tg, R_cw, t_cw, FX, FX, 100.0, 100.0, twist, 1000,
                      np.array([0.0]), np.array([0.0]), eg, burst, 0.24, 0.72, H, b, sw, swr, np.zeros((0, 6)), np.zeros(0))
    return float(swr[0] / sw[0])


def test_the_lag_is_off_by_default_and_leaves_the_kernel_input_as_it_was():
    config = TrackerConfig().event_registration.lag
    assert not config.enabled
    burst = np.zeros(0)
    assert lead_terms(burst, config, FX) is burst


def test_a_lagging_off_event_is_taken_behind_its_edge_by_lag_times_its_speed_above_the_reference():
    # 200 px/s, reference 0.5 rad/s = 100 px/s at FX 200, lag 0.5 ms: the OFF lead falls by 0.05 px.
    config = EventLagConfig(off_lag_us=500.0, reference_mrad_s=500.0)
    burst = lead_terms(np.zeros(0), config, FX)
    assert np.allclose(burst[5:], [0.0, 5e-4, 100.0])
    assert abs(residual(-1, -0.05, burst)) < 1e-9  # on its lead
    assert abs(residual(-1, -0.05, np.zeros(0)) + 0.05) < 1e-9  # without the lag: 0.05 px behind
    assert abs(residual(+1, -0.05, burst) + 0.05) < 1e-9  # ON events keep their lead
    # An edge slower than the reference: the event is taken ahead (1 m/s = 66.7 px/s: +0.0167 px).
    assert abs(residual(-1, 0.5e-3 * (100.0 - FX / 3.0), burst, speed_m_s=1.0)) < 1e-9


def test_the_lag_extends_the_burst_leads_without_turning_them_on():
    config = EventLagConfig(on_lag_us=300.0)
    burst = lead_terms(np.zeros(0), config, FX)
    assert burst.shape == (8,) and burst[0] == 0.0  # follower_crossings stays off
    assert abs(residual(+1, 0.0, burst) - 3e-4 * (200.0 - 0.83 * FX)) < 1e-9  # on the edge: ahead of its lowered lead
    assert abs(residual(-1, 0.0, burst)) < 1e-9
