"""The events' lead by their place in their pixel's burst (``EventRegistrationConfig.follower_crossings``): the pixel
gaps are measured over every event of the step, followers and firsts take their own leads, and the pixel history is
part of the registration's state."""

import numpy as np
from test_event_registration import K, T_REF, TWIST, W, H, error, exact_events, ground_lines, perturbed, registration

from evpose.tracker.event_registration_kernels import NO_EVENT, _pixel_gaps


def test_pixel_gaps_count_from_the_same_pixel_and_polarity_including_dropped_events():
    x = np.array([3, 3, 3, 4, 3], np.uint16)
    y = np.array([2, 2, 2, 2, 2], np.uint16)
    t = np.array([100, 150, 400, 410, 1000], np.int64)
    p = np.array([1, -1, 1, 1, 1], np.int8)
    keep = np.array([True, True, False, True, True])
    last = np.full(2 * 10 * 5, NO_EVENT, np.int64)
    gaps = np.zeros(5, np.int64)
    n = _pixel_gaps(keep, x, y, t, p, 10, last, gaps)
    assert n == 4
    # first ON of (3, 2): none before; the OFF one: none of its polarity; (4, 2): none; the last ON follows the
    # dropped one at 400 us, not the kept one at 100 us.
    assert gaps[0] == 2 ** 62 and gaps[1] == 2 ** 62 and gaps[2] == 2 ** 62 and gaps[3] == 600
    assert last[(2 * 10 + 3) * 2 + 1] == 1000 and last[(2 * 10 + 3) * 2] == 150


def test_followers_and_firsts_take_their_own_leads():
    # Half the events trail their edge by 0.3 px and follow a same-polarity event of their pixel 0.1 ms before (well
    # within one crossing time at the twist's image speeds), the other half lead by 0.1 px and are the first.
    cmap = ground_lines()
    a, b = exact_events(cmap, lead_px=-0.3, polarity=-1, seed=1, n=1500), exact_events(cmap, lead_px=0.1, polarity=-1, seed=2, n=1500)
    order = np.argsort(np.r_[a[2], b[2]], kind="stable")
    events = [np.r_[u, v][order] for u, v in zip(a, b)]
    gaps = np.r_[np.full(1500, 100), np.full(1500, 2 ** 62)][order]
    cfg = dict(follower_crossings=1.0, first_off_lead_px=0.1, follower_off_lead_px=-0.3)
    with_burst = registration(cmap, **cfg).refine(perturbed(), np.arange(len(cmap)), None, *events, T_REF, TWIST, K, None, gaps)
    without = registration(cmap).refine(perturbed(), np.arange(len(cmap)), None, *events, T_REF, TWIST, K, None, gaps)
    all_first = registration(cmap, **cfg).refine(perturbed(), np.arange(len(cmap)), None, *events, T_REF, TWIST, K, None)
    assert np.abs(error(with_burst[0])).max() < 2e-5
    assert np.abs(error(without[0])).max() > 2e-4
    assert np.abs(error(all_first[0])).max() > 2e-4


def test_the_pixel_history_is_snapshotted_and_restored():
    cmap = ground_lines()
    reg = registration(cmap, follower_crossings=1.0)
    reg._pixel_last[7] = 12345
    state = reg.snapshot()
    reg._pixel_last[7] = 99
    reg.restore(state)
    assert reg._pixel_last[7] == 12345 and reg._pixel_last.size == 2 * W * H
    off = registration(cmap)
    assert isinstance(off.snapshot(), np.ndarray)  # off: the state is the offsets alone, as before


def test_the_convex_combination_stays_between_the_two_poses_where_the_full_one_overshoots():
    # Two poses whose informations hold the tilt about y and the shift along x in different combinations (the
    # ambiguity of a camera over flat ground): the full information-weighted mean lands beyond both along x, the
    # convex one between them in every component, with the same covariance.
    import gtsam

    from evpose.tracker.event_registration import combine_poses

    def cov(c):
        C = np.eye(6) * 1e-4
        C[1, 1], C[3, 3], C[1, 3] = 1e-2, 1e-2, c * 1e-2
        C[3, 1] = C[1, 3]
        return C

    T_f = np.eye(4)
    T_e = gtsam.Pose3(gtsam.Rot3.Ry(0.002), gtsam.Point3(0.003, 0.0, 0.0)).matrix()
    full, P_full = combine_poses(T_f, cov(0.99), T_e, cov(-0.99))
    convex, P_convex = combine_poses(T_f, cov(0.99), T_e, cov(-0.99), convex=True)
    e = gtsam.Pose3.Logmap(gtsam.Pose3(T_e))
    x_full, x_convex = gtsam.Pose3.Logmap(gtsam.Pose3(full)), gtsam.Pose3.Logmap(gtsam.Pose3(convex))
    assert np.any((x_full < np.minimum(0, e) - 1e-9) | (x_full > np.maximum(0, e) + 1e-9))
    assert np.all((x_convex >= np.minimum(0, e) - 1e-12) & (x_convex <= np.maximum(0, e) + 1e-12))
    assert np.allclose(P_full, P_convex)
