"""The revision read-out (``FusionConfig.revision_readout_states`` / ``revision_readout_gain``): each state's written
pose moved by the smoother's mean revision of the window's older states, never fed back into the fusion."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.errors import ConfigError
from evpose.fusion.config import FusionConfig
from evpose.fusion.factor_graph import FactorGraphFusion
from evpose.fusion.synthetic import flight_with_registrations

STATES = 5


@pytest.fixture(scope="module")
def flight():
    return flight_with_registrations(1.0, 200.0, seed=4)


def _run(flight, config, stop=None, probe=None):
    cal, imu, (t0, T0, v0), times, regs, cov = flight
    f = FactorGraphFusion(config, cal)
    f.add_imu(imu)
    f.initialize(t0, T0, v0)
    states = []
    for k, (t, T) in enumerate(zip(times, regs)):
        if stop is not None and k == stop:
            break
        states.append(f.update(int(t), T, None if T is None else cov))
        if probe is not None:
            probe(k, f, states[-1])
    return f, states


def test_readout_leaves_every_fused_state_bit_identical(flight):
    _, off = _run(flight, FusionConfig(revision_readout_states=0))
    _, on = _run(flight, FusionConfig(revision_readout_states=STATES, revision_readout_gain=2.0))
    assert len(off) == len(on)
    for a, b in zip(off, on):
        assert np.array_equal(a.T_world_cam, b.T_world_cam)
        assert np.array_equal(a.velocity_world, b.velocity_world)
        assert a.readout_T_world_cam is None
    # It needs STATES older states: none for the first updates after initialize (state 0), then always one.
    assert all(s.readout_T_world_cam is None for s in on[: STATES - 1])
    assert all(s.readout_T_world_cam is not None for s in on[STATES - 1 :])
    moved = [np.linalg.norm(s.readout_T_world_cam[:3, 3] - s.T_world_cam[:3, 3]) for s in on[STATES:]]
    assert max(moved) > 1e-5  # the smoother does revise the older states


def test_readout_is_the_gain_times_the_mean_revision(flight):
    config = FusionConfig(revision_readout_states=STATES, revision_readout_gain=1.5, revision_readout_depth_ratio=1.0,
                          revision_readout_position_smoothing=1.0)  # the plain formula, no depth ratio or smoothing
    checked = []

    def probe(k, f, state):
        if k not in (40, 77, 110):
            return
        # By hand: each older state's smoothed pose now against the pose written when it was the newest.
        rot, pos = np.zeros(3), np.zeros(3)
        for lag in range(1, STATES + 1):
            then = f.extrinsic.cam_pose(f.history[-1 - lag][1].pose().matrix())
            now = f.extrinsic.cam_pose(f.smoother.calculateEstimatePose3(f._keys(f.index - lag)[0]).matrix())
            rot += Rotation.from_matrix(now[:3, :3] @ then[:3, :3].T).as_rotvec() / STATES
            pos += (now[:3, 3] - then[:3, 3]) / STATES
        T = state.T_world_cam
        assert np.allclose(state.readout_T_world_cam[:3, 3], T[:3, 3] + 1.5 * pos, atol=1e-12)
        R = Rotation.from_rotvec(1.5 * rot).as_matrix() @ T[:3, :3]
        assert np.allclose(state.readout_T_world_cam[:3, :3], R, atol=1e-12)
        checked.append(k)

    _run(flight, config, probe=probe)
    assert checked == [40, 77, 110]


def test_gain_zero_writes_the_fused_pose(flight):
    _, states = _run(flight, FusionConfig(revision_readout_states=STATES, revision_readout_gain=0.0), stop=60)
    for s in states[STATES:]:
        assert np.allclose(s.readout_T_world_cam, s.T_world_cam, atol=1e-15)


def test_a_restored_fusion_reads_out_as_the_uninterrupted_one(flight):
    config = FusionConfig(revision_readout_states=STATES, revision_readout_gain=2.0)
    cal, imu, (t0, T0, v0), times, regs, cov = flight
    _, ref = _run(flight, config)
    f, _ = _run(flight, config, stop=50)
    snap = f.snapshot()
    g = FactorGraphFusion(config, cal)
    g.restore(snap)
    for k in range(50, 90):
        s = g.update(int(times[k]), regs[k], None if regs[k] is None else cov)
        assert np.array_equal(s.readout_T_world_cam, ref[k].readout_T_world_cam)


def test_config_refuses_negative_values_and_uses_at_most_the_window(flight):
    with pytest.raises(ConfigError, match="revision_readout_states"):
        FusionConfig(revision_readout_states=-1).validate()
    with pytest.raises(ConfigError, match="revision_readout_gain"):
        FusionConfig(revision_readout_gain=-1.0).validate()
    assert FusionConfig().revision_readout_states == 7 and FusionConfig().revision_readout_gain == 2.0  # on by default
    # More states than the window keeps older ones: the window's own (window_states - 1 = 3) are used.
    short = FusionConfig(window_states=4, revision_readout_states=7)
    _, states = _run(flight, short, stop=30)
    same = FusionConfig(window_states=4, revision_readout_states=3)
    _, ref = _run(flight, same, stop=30)
    assert states[1].readout_T_world_cam is None and states[2].readout_T_world_cam is not None
    for a, b in zip(states, ref):
        assert (a.readout_T_world_cam is None and b.readout_T_world_cam is None) or np.array_equal(a.readout_T_world_cam, b.readout_T_world_cam)


def test_moved_like_carries_a_correction_onto_another_pose():
    from evpose.fusion.revision_readout import moved_like

    rng = np.random.default_rng(2)
    def pose(rv, p):
        T = np.eye(4)
        T[:3, :3] = Rotation.from_rotvec(rv).as_matrix()
        T[:3, 3] = p
        return T
    A = pose(rng.normal(0, 0.3, 3), rng.normal(0, 1, 3))
    B = pose(rng.normal(0, 0.3, 3), rng.normal(0, 1, 3))
    dR = Rotation.from_rotvec([1e-3, -2e-3, 5e-4]).as_matrix()
    A2 = A.copy()
    A2[:3, :3] = dR @ A[:3, :3]
    A2[:3, 3] += [0.002, -0.001, 0.003]
    B2 = moved_like(B, A, A2)
    assert np.allclose(B2[:3, :3], dR @ B[:3, :3], atol=1e-14)
    assert np.allclose(B2[:3, 3], B[:3, 3] + [0.002, -0.001, 0.003], atol=1e-15)
    assert np.allclose(moved_like(B, A, A), B, atol=1e-14)
