"""Per-point leads from the events per pixel passage (``EventRegistrationConfig.contrast``,
:mod:`evpose.tracker.contrast_leads`): the coverage model against the simulator's ESIM, the running counts, the leads
they add and the state they keep."""

import numpy as np
from test_event_registration import K, T_REF, TWIST, error, exact_events, ground_lines, perturbed, registration

from evpose.sim.esim import EsimConfig, EventGenerator
from evpose.sim.render import subpixel_pattern
from evpose.tracker.contrast_leads import ContrastLeadConfig, PassageCounts, coverage_lead

C = 0.4


def _esim_lead(dL: float, angle: float, history: str, width: int = 300) -> float:
    """Mean lead (px along the motion) of the ESIM events of a straight edge of log contrast ``dL`` (bright side
    growing) sweeping a row of pixels rendered as the simulator does (3x3 n-rooks samples, a render every 0.5 px),
    each pixel's reference left by a previous passage of the same ('same') or the opposite ('opposite') polarity."""
    rng = np.random.default_rng(3)
    n = np.array([np.cos(angle), np.sin(angle)])
    S = subpixel_pattern(3)
    Lm, Lp = np.log(0.2), np.log(0.2) + dL
    px = np.stack([np.arange(width), np.zeros(width)], 1).astype(float)
    q = (px[:, None, :] + S[None]) @ n

    def image(xe):  # the edge line {p: p.n = xe}, bright on its +n side; it moves towards -n
        f = (q > xe).mean(1)
        return np.log(f * np.exp(Lp) + (1 - f) * np.exp(Lm))

    gen = EventGenerator(EsimConfig(c_sigma=0.0), width, 1, rng)
    x0, x1 = (px @ n).max() + 2, (px @ n).min() - 2
    base = image(x0)
    sign = 1.0 if history == "opposite" else -1.0  # come down (OFF) or up (ON) to the start level
    gen.reset(base + sign * rng.uniform(1, 3, width), 0)
    gen.step(base, 1000)
    speed, xe, t, out = 100.0, x0, 1000, []
    while xe > x1:
        xe -= 0.5
        t += int(0.5 / speed * 1e6)
        out.append(gen.step(image(xe), t))
    ts = np.concatenate([e.t for e in out])
    xs = np.concatenate([e.x for e in out]).astype(float)
    edge = x0 - (ts - 1000) * 1e-6 * speed
    return float(np.mean(edge - xs * n[0]))  # ahead along the motion (-n): the edge's position less the pixel's


def test_the_coverage_model_gives_the_simulated_esim_lead_of_an_edge():
    angle = 0.3
    m = -np.array([np.cos(angle), np.sin(angle)])
    Lm = np.log(0.2)
    got = {}
    for dL in (1.2, 2.0):
        for history, gap in (("opposite", C), ("same", 0.0)):
            sim = _esim_lead(dL, angle, history)
            model = coverage_lead(Lm, Lm + dL, m, gap, np.inf, subpixel_pattern(3))
            assert abs(sim - model) < 0.05, (dL, history, sim, model)
            got[dL, history] = sim
    # after an opposite passage the first event needs a full threshold more: the events trail, the more so the
    # weaker the edge; after a same-polarity one they lead (the concave log of the pixel's mixed intensity)
    assert got[1.2, "opposite"] < got[2.0, "opposite"] < got[2.0, "same"]
    assert got[1.2, "same"] > 0 and got[1.2, "opposite"] < -0.05


def test_the_coverage_model_of_a_darkening_edge_mirrors_the_brightening_one():
    m = np.array([np.cos(0.4), np.sin(0.4)])
    on = coverage_lead(0.0, 1.5, m, 0.0, np.inf, subpixel_pattern(3))
    off = coverage_lead(1.5, 0.0, m, 0.0, np.inf, subpixel_pattern(3))
    assert on > 0.05 and abs(on + off) < 1e-12  # ON events lead, OFF events trail, by the same amount
    assert np.isnan(coverage_lead(0.0, 0.3, m, C, np.inf, subpixel_pattern(3)))  # weaker than the carried-over gap: no event


def _one_point(events_per_passage: int, passages: int, cfg: ContrastLeadConfig, follower_gap_us: int = 1000) -> PassageCounts:
    # One map point 5 m ahead on a vertical edge; the camera moving sideways at 1 m/s: 20 px/s at F = 100 px, one
    # pixel crossing 50 ms. A passage: one event whose pixel was quiet for 1 s, then followers `follower_gap_us` apart.
    counts = PassageCounts(cfg, 3)
    pts, tg = np.array([[0.0, 0.0, 5.0]]), np.array([[0.0, 1.0, 0.0]])
    twist = np.array([0.0, 0.0, 0.0, -1.0, 0.0, 0.0])
    gaps = np.tile(np.r_[1_000_000, np.full(events_per_passage - 1, follower_gap_us)], passages).astype(np.int64)
    counts.update(gaps.size, np.zeros(gaps.size, np.int64), np.array([1]), pts, tg, gaps, np.eye(3), np.zeros(3), K, twist)
    return counts


def test_the_running_events_per_passage_converge_to_the_pixels_passage_size():
    cfg = ContrastLeadConfig(memory_events=50.0)
    for k in (1, 2, 3):
        r = _one_point(k, 60, cfg).ratio()
        assert abs(r[1] - k) < 0.05 * k and np.isnan(r[0]) and np.isnan(r[2])
    # followers further apart than `crossings` crossing times (2 x 50 ms) start passages of their own
    far = _one_point(3, 60, cfg, follower_gap_us=150_000)
    assert abs(far.ratio()[1] - 1.0) < 1e-9
    near = _one_point(3, 60, cfg, follower_gap_us=90_000)
    assert abs(near.ratio()[1] - 3.0) < 0.15


def test_only_points_firing_one_event_per_passage_take_the_lead():
    cfg = ContrastLeadConfig(lone_on_lead_px=-0.1, lone_off_lead_px=-0.1)
    for k, expect in ((1, -0.1), (2, 0.0)):
        counts = _one_point(k, 30, cfg)
        on, off = np.array([0.05, 0.05]), np.array([-0.1, -0.1])
        counts.add_leads(np.array([1, 0]), on, off)
        assert np.allclose(on, [0.05 + expect, 0.05]) and np.allclose(off, [-0.1 + expect, -0.1])
    few = _one_point(1, 5, cfg)  # 5 events: below min_events, no lead yet
    on, off = np.zeros(1), np.zeros(1)
    few.add_leads(np.array([1]), on, off)
    assert on[0] == 0 and off[0] == 0


def test_each_polarity_of_a_lone_point_takes_its_own_lead():
    counts = _one_point(1, 30, ContrastLeadConfig(lone_on_lead_px=-0.2, lone_off_lead_px=0.05))
    on, off = np.array([0.05, 0.05]), np.array([-0.1, -0.1])
    counts.add_leads(np.array([1, 0]), on, off)
    assert np.allclose(on, [-0.15, 0.05]) and np.allclose(off, [-0.05, -0.1])


def test_the_registration_takes_the_lone_points_lead_out():
    # Every (OFF) event trails its edge by 0.1 px and starts its pixel's passage: the OFF lone lead takes that out;
    # the ON one, far off, touches no OFF event.
    cmap = ground_lines()
    events = exact_events(cmap, lead_px=-0.1, polarity=-1, seed=1, n=3000)
    gaps = np.full(3000, 2 ** 62)
    used = np.arange(len(cmap))
    on = registration(cmap, contrast=ContrastLeadConfig(lone_on_lead_px=-0.5, lone_off_lead_px=-0.1, min_events=0.0))
    with_lead = on.refine(perturbed(), used, None, *events, T_REF, TWIST, K, None, gaps)
    without = registration(cmap).refine(perturbed(), used, None, *events, T_REF, TWIST, K, None, gaps)
    assert np.abs(error(with_lead[0])).max() < 2e-5
    assert np.abs(error(without[0])).max() > 2e-4


def test_the_counts_are_snapshotted_and_restored_and_off_keeps_the_old_state():
    cmap = ground_lines()
    reg = registration(cmap, contrast=ContrastLeadConfig(lone_on_lead_px=-0.1))
    assert reg._pixel_last is not None  # the pixel history is kept for the passages
    reg._passages.events[4], reg._passages.starts[4] = 7.0, 3.0
    state = reg.snapshot()
    reg._passages.events[4] = 1.0
    reg.restore(state)
    assert reg._passages.events[4] == 7.0 and reg._passages.starts[4] == 3.0
    reg.restore(state[0])  # offsets alone: a fresh start
    assert not reg._passages.events.any()
    off = registration(cmap)
    assert off._passages is None and isinstance(off.snapshot(), np.ndarray)
    assert registration(cmap, contrast=ContrastLeadConfig(lone_on_lead_px=0.0, lone_off_lead_px=-0.1))._passages is not None


def test_the_option_reads_from_a_config_file_mapping():
    from evpose.io.config_file import config_from_dict
    from evpose.tracker.config import TrackerConfig

    cfg = config_from_dict(TrackerConfig, {"event_registration": {"contrast": {"lone_on_lead_px": -0.05, "lone_off_lead_px": 0.02,
                                                                              "lone_max_ratio": 1.3}}})
    c = cfg.event_registration.contrast
    assert c.lone_on_lead_px == -0.05 and c.lone_off_lead_px == 0.02 and c.lone_max_ratio == 1.3
    # on by default since session 42, its counts pooled along each edge
    default = TrackerConfig().event_registration.contrast
    assert default.lone_on_lead_px == -0.2 and default.lone_off_lead_px == -0.05 and default.pool_radius_m == 0.05
    cfg = config_from_dict(TrackerConfig, {"event_registration": {"contrast": {"lone_on_lead_px": 0.0, "pool_radius_m": 0.0}}})
    assert cfg.event_registration.contrast.lone_on_lead_px == 0.0 and cfg.event_registration.contrast.pool_radius_m == 0.0
