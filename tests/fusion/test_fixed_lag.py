import gtsam
import numpy as np
import pytest

from evpose.fusion import fixed_lag
from evpose.fusion.config import FusionConfig
from evpose.fusion.factor_graph import FactorGraphFusion
from evpose.fusion.fixed_lag import CopyableFixedLagSmoother, keys_to_reeliminate, parse_bayes_tree

from fusion_helpers import WHITE, make_motion, noisy_registrations

X = gtsam.symbol_shorthand.X


def _dot(*cliques, edges=()):
    """A dot text as ISAM2.dot prints it: cliques as (id, label), edges as (parent id, child id)."""
    lines = ["digraph G{"] + [f'{i}[label="{label}"];' for i, label in cliques] + [f"{a}->{b}" for a, b in edges] + ["}"]
    return "\n".join(lines)


def test_bayes_tree_is_parsed_from_the_dot_text_of_isam2():
    isam = gtsam.ISAM2(gtsam.ISAM2Params())
    graph, values = gtsam.NonlinearFactorGraph(), gtsam.Values()
    noise = gtsam.noiseModel.Isotropic.Sigma(6, 0.1)
    graph.add(gtsam.PriorFactorPose3(X(0), gtsam.Pose3(), noise))
    values.insert(X(0), gtsam.Pose3())
    for i in range(1, 4):
        graph.add(gtsam.BetweenFactorPose3(X(i - 1), X(i), gtsam.Pose3(), noise))
        values.insert(X(i), gtsam.Pose3())
    isam.update(graph, values)
    cliques, children, owner = parse_bayes_tree(isam.dot())
    assert sorted(owner) == ["x0", "x1", "x2", "x3"]
    assert sum(len(f) for f, _ in cliques.values()) == 4
    roots = [c for c in cliques if not cliques[c][1]]
    assert len(roots) == 1 and sum(len(v) for v in children.values()) == len(cliques) - 1


def test_keys_to_reeliminate_marks_cliques_that_keep_a_marginalised_key_from_being_a_leaf():
    chain = _dot(("3", "x3, x2"), ("1", "x1 : x2"), ("0", "x0 : x1"), edges=(("3", "1"), ("1", "0")))
    assert keys_to_reeliminate(chain, {"x0"}) == set()  # already a leaf
    # x1's child depends on it and holds a kept key: both cliques are re-eliminated.
    assert keys_to_reeliminate(chain, {"x1"}) == {"x1", "x0"}
    assert keys_to_reeliminate(chain, {"x1", "x0"}) == set()  # the whole subtree goes
    # A kept key eliminated before the marginalised one in the same clique.
    mixed = _dot(("3", "x3"), ("2", "x2, x1 : x3"), edges=(("3", "2"),))
    assert keys_to_reeliminate(mixed, {"x1"}) == {"x2", "x1"}


def test_the_leaf_fast_path_agrees_with_the_full_analysis():
    chain = _dot(("13", "x3, x2"), ("11", "x1 : x2"), ("10", "x0 : x1"), edges=(("13", "11"), ("11", "10")))
    assert fixed_lag._only_in_leaf_cliques(chain, {10: "x0"})
    assert not fixed_lag._only_in_leaf_cliques(chain, {11: "x1"})
    assert not fixed_lag._only_in_leaf_cliques(chain.replace("10[", "99["), {10: "x0"})  # unknown naming: full analysis


class _NeverRebased(FactorGraphFusion):
    rebase_every_states = 0


class _GtsamSmootherFusion(FactorGraphFusion):
    def _new_smoother(self):
        s = super()._new_smoother()
        return gtsam.IncrementalFixedLagSmoother(s.lag, s.params)


@pytest.mark.parametrize("window", [3, 8])
def test_estimates_equal_gtsam_incremental_fixed_lag_smoother_bit_for_bit(window, calibration, monkeypatch):
    marked = []
    full = fixed_lag.keys_to_reeliminate
    monkeypatch.setattr(fixed_lag, "keys_to_reeliminate", lambda dot, m: marked.append(full(dot, m)) or marked[-1])
    m = make_motion(duration_s=1.3, imu_rate_hz=500.0, acc_bias=(0.08, -0.05, 0.1), gyro_bias=(0.01, -0.02, 0.015),
                    accel_noise_density=2e-3, gyro_noise_density=1.7e-4, seed=2)
    times = m.config.t0_us + np.arange(5000, 1_250_000, 5000)
    _, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.005, np.radians(0.3), seed=3)
    rng = np.random.default_rng(4)
    for k in range(len(regs)):
        if rng.random() < 0.03:
            regs[k] = regs[k].copy()
            regs[k][:3, 3] += rng.normal(0, 0.1, 3)  # a gross outlier
    regs = [None if 80 <= k < 110 else T for k, T in enumerate(regs)]  # a tracking loss
    # gtsam's ordering, and no forced relinearisation (gtsam's smoother has no such call)
    cfg = FusionConfig(window_states=window, reoptimize_every=3, newest_state_last=False, relinearize_correction_velocity=0.0, **WHITE)
    fused = []
    for cls in (_NeverRebased, _GtsamSmootherFusion):
        f = cls(cfg, calibration)
        f.add_imu(m.imu())
        t0 = m.config.t0_us
        f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
        fused.append([f.update(int(t), regs[k], cov) for k, t in enumerate(times)])
    for a, b in zip(*fused):
        assert np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.velocity_world, b.velocity_world)
        assert np.array_equal(a.acc_bias, b.acc_bias) and np.array_equal(a.covariance, b.covariance)
    assert any(marked), "the run never needed extra re-elimination: the helper went untested"


def test_the_newest_state_last_puts_it_at_the_root_and_moves_the_estimates_by_rounding_only(calibration):
    m = make_motion(duration_s=1.3, imu_rate_hz=500.0, acc_bias=(0.08, -0.05, 0.1), gyro_bias=(0.01, -0.02, 0.015),
                    accel_noise_density=2e-3, gyro_noise_density=1.7e-4, seed=2)
    times = m.config.t0_us + np.arange(5000, 1_250_000, 5000)
    _, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.005, np.radians(0.3), seed=3)
    regs = [None if 80 <= k < 110 else T for k, T in enumerate(regs)]  # a tracking loss (re-acquisition too)
    runs, roots = [], []
    for last in (False, True):
        # Without the forced relinearisations of the start and the re-acquisition (relinearize_correction_velocity),
        # which leave the newest state in a child for those updates.
        f = _NeverRebased(FusionConfig(newest_state_last=last, relinearize_correction_velocity=0.0, **WHITE), calibration)
        f.add_imu(m.imu())
        t0 = m.config.t0_us
        f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
        assert f.smoother.newest_last is last and f.smoother.copy().newest_last is last
        states, at_root = [], 0
        for k, t in enumerate(times):
            states.append(f.update(int(t), regs[k], cov))
            cliques, _, owner = parse_bayes_tree(f.smoother.isam.dot())
            at_root += not cliques[owner[gtsam.DefaultKeyFormatter(X(f.index))]][1]  # the newest pose's clique has no parents
        runs.append(states)
        roots.append(at_root)
    # (A relinearising window re-optimisation, which adds no factor, may leave it in a child now and then.)
    assert roots[1] > 0.95 * len(times) and roots[0] < 0.5 * len(times)
    for a, b in zip(*runs):
        assert np.abs(a.T_world_cam - b.T_world_cam).max() < 1e-8 and np.abs(a.velocity_world - b.velocity_world).max() < 1e-7
        assert np.allclose(a.covariance, b.covariance, rtol=1e-6, atol=1e-14) and a.degraded == b.degraded
    assert any(not np.array_equal(a.T_world_cam, b.T_world_cam) for a, b in zip(*runs))  # another elimination order


def test_a_copy_is_independent_and_continues_identically():
    noise = gtsam.noiseModel.Isotropic.Sigma(6, 0.1)
    params = gtsam.ISAM2Params()
    s = CopyableFixedLagSmoother(3.0, params)
    graph, values = gtsam.NonlinearFactorGraph(), gtsam.Values()
    graph.add(gtsam.PriorFactorPose3(X(0), gtsam.Pose3(), noise))
    values.insert(X(0), gtsam.Pose3())
    s.update(graph, values, {X(0): 0.0})
    step = gtsam.Pose3(gtsam.Rot3.Rz(0.1), np.array([0.3, 0.0, 0.05]))

    def add(sm, i):
        g, v = gtsam.NonlinearFactorGraph(), gtsam.Values()
        g.add(gtsam.BetweenFactorPose3(X(i - 1), X(i), step, noise))
        g.add(gtsam.PriorFactorPose3(X(i), gtsam.Pose3(gtsam.Rot3.Rz(0.1 * i), np.array([0.3 * i, 0.01 * i, 0.0])), noise))
        v.insert(X(i), sm.calculateEstimatePose3(X(i - 1)).compose(step))
        sm.update(g, v, {X(i): float(i)})

    for i in range(1, 8):
        add(s, i)
    c = s.copy()
    before = c.calculateEstimatePose3(X(7)).matrix()
    for i in range(8, 12):
        add(s, i)
    assert np.array_equal(c.calculateEstimatePose3(X(7)).matrix(), before)  # the original moved on, the copy did not
    del s
    d = c.copy()
    for i in range(8, 12):
        add(c, i)
        add(d, i)
        assert np.array_equal(c.calculateEstimatePose3(X(i)).matrix(), d.calculateEstimatePose3(X(i)).matrix())
    assert not c.isam.valueExists(X(7))  # lag 3: marginalised


def _flight(calibration, seconds=1.3, **config):
    m = make_motion(duration_s=seconds, imu_rate_hz=500.0, acc_bias=(0.08, -0.05, 0.1), gyro_bias=(0.01, -0.02, 0.015),
                    accel_noise_density=2e-3, gyro_noise_density=1.7e-4, seed=2)
    times = m.config.t0_us + np.arange(5000, int(seconds * 1e6) - 50_000, 5000)
    _, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.005, np.radians(0.3), seed=3)
    regs = [None if 130 <= k < 150 else T for k, T in enumerate(regs)]  # a tracking loss across a re-base

    def start(cls=FactorGraphFusion):
        f = cls(FusionConfig(**{**WHITE, **config}), calibration)
        f.add_imu(m.imu())
        t0 = m.config.t0_us
        f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0),
                     m.camera_velocity([t0], calibration.T_cam_imu)[0])
        return f

    return start, times, regs, cov


def _round_trip(entries):
    """The journal entries through gtsam's serialisation, as a disk snapshot stores them."""
    out = []
    for e in entries:
        if e[0] in ("update", "rebase"):
            g, v = gtsam.NonlinearFactorGraph(), gtsam.Values()
            if e[1] is not None:
                g.deserialize(e[1].serialize())
            if e[2] is not None:
                v.deserialize(e[2].serialize())
            e = (e[0], g if e[1] is not None else None, v if e[2] is not None else None, *e[3:])
        out.append(e)
    return out


@pytest.mark.parametrize("error_model", ["white", "ar1_whitened"])
def test_a_re_based_smoother_equals_its_rebuild_from_the_stored_content_and_journal_since_bit_for_bit(error_model, calibration):
    # ar1_whitened removes a factor at every registration: removals are journalled and renumbered by each re-base.
    start, times, regs, cov = _flight(calibration, registration_error_model=error_model)
    f = start()
    fresh = f.smoother.copy()  # step 0's: what a restore starts from
    f.smoother.journal = []
    deep = 237  # off any multiple of the re-base period (50 states) and of the re-optimisation cadence
    for k in range(deep):
        f.update(int(times[k]), regs[k], cov)
    journal = f.smoother.journal
    assert journal[0][0] == "rebase"  # the journal restarted at the last re-base (state 200)
    # Since then: the update that made state 200 and the 37 after it (plus re-optimisations and estimate reads).
    assert sum(e[0] == "update" and e[3] is not None for e in journal) == deep - 199
    if error_model != "white":
        assert any(len(e) > 4 and e[4] for e in journal if e[0] == "update")
    fresh.replay(_round_trip(journal))
    assert fresh.isam.dot() == f.smoother.isam.dot()
    g = start()
    snap = f.snapshot()
    g.restore({**snap, "smoother": fresh})
    for k in range(deep, len(times)):
        a, b = f.update(int(times[k]), regs[k], cov), g.update(int(times[k]), regs[k], cov)
        assert np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.velocity_world, b.velocity_world)
        assert np.array_equal(a.gyro_bias, b.gyro_bias) and np.array_equal(a.covariance, b.covariance)


def test_re_bases_move_the_estimates_by_much_less_than_their_error(calibration):
    start, times, regs, cov = _flight(calibration)
    runs = []
    for cls in (FactorGraphFusion, _NeverRebased):
        f = start(cls)
        runs.append(np.array([f.update(int(t), regs[k], cov).T_world_cam[:3, 3] for k, t in enumerate(times)]))
    moved = np.linalg.norm(runs[0] - runs[1], axis=1)
    assert moved[:49].max() == 0.0 < moved.max()  # identical until the first re-base (at state 50), then not quite
    assert moved.max() < 5e-4  # < 0.5 mm, against registrations of 5 mm noise
