import numpy as np

from evpose.slam.config import EventImageConfig, MciConfig, SlamConfig
from evpose.slam.event_window import ReconstructionWindow
from evpose.slam.mci import Hypothesis, MciGenerator, MotionPrior, reference_time_us

K = np.array([[150.0, 0, 80], [0, 150.0, 60], [0, 0, 1]])
W, H = 160, 120


def _static_window(n_overlap: int, seed=0, n_pts=50, per_pt=40, span_us=20_000):
    """Still dots: no feature tracks, so H4 is the only hypothesis; the first ``n_overlap`` events are the previous
    window's."""
    rng = np.random.default_rng(seed)
    p0 = np.c_[rng.uniform(10, 150, n_pts), rng.uniform(10, 110, n_pts)]
    t = np.sort(rng.integers(0, span_us, n_pts * per_pt)).astype(np.int64)
    j = rng.integers(0, n_pts, t.size)
    none = np.zeros((0, 2), np.float32)
    return ReconstructionWindow(t, p0[j, 0], p0[j, 1], np.ones(t.size, np.int8), none, none, 0, 0, 1, 0.0, n_overlap=n_overlap)


def test_unwarped_own_events_renders_h4_from_the_windows_new_events_and_stamps_it_at_their_middle():
    rw = _static_window(n_overlap=1000)
    on = MciGenerator(MciConfig(unwarped_own_events=True), EventImageConfig(use_polarity=False, sigma_px=0.0), K, W, H)
    off = MciGenerator(MciConfig(), EventImageConfig(use_polarity=False, sigma_px=0.0), K, W, H)
    a, b = on.generate(rw, MotionPrior()), off.generate(rw, MotionPrior())
    assert a.hypothesis is Hypothesis.H4_NONE and b.hypothesis is Hypothesis.H4_NONE
    # Every event adds a mass of one: the image holds only the events past the overlap.
    assert np.isclose(a.image.sum(), len(rw.t) - 1000) and np.isclose(b.image.sum(), len(rw.t))
    frac = MciConfig().reference_fraction
    assert a.t_us == reference_time_us(rw.t[1000:], frac) > b.t_us == reference_time_us(rw.t, frac)
    assert a.t_by_hypothesis == {"H4": a.t_us, "window": b.t_us} and b.t_by_hypothesis == {}


def test_unwarped_own_events_leaves_a_window_without_overlap_as_it_was():
    rw = _static_window(n_overlap=0)
    cfg = EventImageConfig(use_polarity=False, sigma_px=0.0)
    a = MciGenerator(MciConfig(unwarped_own_events=True), cfg, K, W, H).generate(rw, MotionPrior())
    b = MciGenerator(MciConfig(), cfg, K, W, H).generate(rw, MotionPrior())
    assert a.t_us == b.t_us and np.array_equal(a.image, b.image) and a.t_by_hypothesis == {}


def test_unwarped_own_events_is_off_by_default():
    assert SlamConfig().mci.unwarped_own_events is False


def test_before_map_renders_own_events_only_while_no_map_is_tracked():
    rw = _static_window(n_overlap=1000)
    cfg = EventImageConfig(use_polarity=False, sigma_px=0.0)
    gen = MciGenerator(MciConfig(unwarped_own_events_before_map=True), cfg, K, W, H)
    a, b = gen.generate(rw, MotionPrior(), mapped=False), gen.generate(rw, MotionPrior(), mapped=True)
    assert np.isclose(a.image.sum(), len(rw.t) - 1000) and np.isclose(b.image.sum(), len(rw.t))
    assert a.time_of("H4") == a.t_us and a.time_of("H2") == b.t_us == b.time_of("H4")
