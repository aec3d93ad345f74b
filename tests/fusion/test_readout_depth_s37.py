"""The read-out's depth ratio (``FusionConfig.revision_readout_depth_ratio``): the position revision's component along
the fused camera's optical axis gets ``revision_readout_depth_ratio`` times the gain; everything else as before."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.errors import ConfigError
from evpose.fusion.config import FusionConfig
from evpose.fusion.factor_graph import FactorGraphFusion
from evpose.fusion.revision_readout import revised_pose
from evpose.fusion.synthetic import flight_with_registrations

STATES = 5


@pytest.fixture(scope="module")
def flight():
    return flight_with_registrations(1.0, 200.0, seed=7)


def _states(flight, config, stop=180):
    cal, imu, (t0, T0, v0), times, regs, cov = flight
    f = FactorGraphFusion(config, cal)
    f.add_imu(imu)
    f.initialize(t0, T0, v0)
    return [f.update(int(t), T, None if T is None else cov) for t, T in zip(times[:stop], regs[:stop])]


def test_revised_pose_scales_only_the_optical_axis_component():
    import gtsam

    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.4, -0.2, 1.1]).as_matrix()
    T[:3, 3] = [1.0, -2.0, 3.0]
    axis = T[:3, 2]
    rot = np.array([1e-3, -2e-3, 5e-4])
    pos = np.array([0.004, -0.003, 0.002])
    plain = revised_pose(gtsam, T, rot, pos, 2.0)
    deep = revised_pose(gtsam, T, rot, pos, 2.0, depth_ratio=2.5)
    assert np.array_equal(deep[:3, :3], plain[:3, :3])  # rotation untouched
    step_plain, step_deep = plain[:3, 3] - T[:3, 3], deep[:3, 3] - T[:3, 3]
    along = axis @ pos
    assert np.isclose(axis @ step_plain, 2.0 * along, atol=1e-15)
    assert np.isclose(axis @ step_deep, 5.0 * along, atol=1e-15)
    # Across the optical axis both move the same.
    across = lambda v: v - (axis @ v) * axis  # noqa: E731
    assert np.allclose(across(step_deep), across(step_plain), atol=1e-15)
    assert np.array_equal(revised_pose(gtsam, T, rot, pos, 2.0, depth_ratio=1.0), plain)


def test_depth_ratio_moves_only_the_written_depth(flight):
    plain = dict(revision_readout_states=STATES, revision_readout_position_smoothing=1.0)
    one = _states(flight, FusionConfig(revision_readout_depth_ratio=1.0, **plain))
    two = _states(flight, FusionConfig(revision_readout_depth_ratio=2.0, **plain))
    moved = 0.0
    t0 = flight[2][0]
    startup_us = FusionConfig().registration_startup_s * 1e6
    early = late = 0
    for a, b in zip(one, two):
        # The fusion itself is the same bit for bit: only the written pose differs.
        assert np.array_equal(a.T_world_cam, b.T_world_cam)
        assert np.array_equal(a.velocity_world, b.velocity_world)
        if a.readout_T_world_cam is None:
            assert b.readout_T_world_cam is None
            continue
        assert np.array_equal(a.readout_T_world_cam[:3, :3], b.readout_T_world_cam[:3, :3])
        if a.t_us - t0 < startup_us:
            # Within the registrations' start-up widening the ratio is not applied.
            assert np.array_equal(a.readout_T_world_cam, b.readout_T_world_cam)
            early += 1
            continue
        late += 1
        axis = a.T_world_cam[:3, 2]
        da = a.readout_T_world_cam[:3, 3] - a.T_world_cam[:3, 3]
        db = b.readout_T_world_cam[:3, 3] - b.T_world_cam[:3, 3]
        # Twice the gain along the optical axis, the same across it.
        assert np.isclose(axis @ db, 2.0 * (axis @ da), rtol=1e-9, atol=1e-15)
        assert np.allclose(db - (axis @ db) * axis, da - (axis @ da) * axis, atol=1e-14)
        moved = max(moved, abs(axis @ da))
    assert moved > 1e-6  # the smoother did revise depth, so the test saw the ratio act
    assert early > 10 and late > 10


def test_depth_ratio_must_not_be_negative():
    assert FusionConfig().revision_readout_depth_ratio == 2.0 and FusionConfig().revision_readout_position_smoothing == 0.5
    FusionConfig(revision_readout_depth_ratio=0.0).validate()
    with pytest.raises(ConfigError, match="revision_readout_depth_ratio"):
        FusionConfig(revision_readout_depth_ratio=-0.5).validate()


def test_position_smoothing_is_a_causal_average_of_the_corrections(flight):
    raw = _states(flight, FusionConfig(revision_readout_states=STATES, revision_readout_depth_ratio=2.0,
                                       revision_readout_position_smoothing=1.0))
    smooth = _states(flight, FusionConfig(revision_readout_states=STATES, revision_readout_depth_ratio=2.0,
                                          revision_readout_position_smoothing=0.4))
    last = None
    seen = 0
    for a, b in zip(raw, smooth):
        assert np.array_equal(a.T_world_cam, b.T_world_cam)  # only the written pose changes
        if a.readout_T_world_cam is None:
            assert b.readout_T_world_cam is None
            last = None
            continue
        assert np.array_equal(a.readout_T_world_cam[:3, :3], b.readout_T_world_cam[:3, :3])  # rotation untouched
        own = a.readout_T_world_cam[:3, 3] - a.T_world_cam[:3, 3]
        written = b.readout_T_world_cam[:3, 3] - b.T_world_cam[:3, 3]
        # The first read-out after the start is its own correction; then 0.4 x its own + 0.6 x the last written one.
        expected = own if last is None else 0.4 * own + 0.6 * last
        assert np.allclose(written, expected, rtol=0, atol=1e-15)
        last = written
        seen += 1
    assert seen > 100
    jitter = lambda s: np.mean([np.linalg.norm(np.diff([x.readout_T_world_cam[:3, 3] - x.T_world_cam[:3, 3] for x in s[STATES:]], axis=0), axis=1)])  # noqa: E731
    assert jitter(smooth) < 0.8 * jitter(raw)  # the corrections change less from one update to the next


def test_smoothing_survives_snapshot_and_restore(flight):
    config = FusionConfig(revision_readout_states=STATES, revision_readout_position_smoothing=0.5)
    cal, imu, (t0, T0, v0), times, regs, cov = flight
    ref = _states(flight, config, stop=90)
    f = FactorGraphFusion(config, cal)
    f.add_imu(imu)
    f.initialize(t0, T0, v0)
    for k in range(50):
        f.update(int(times[k]), regs[k], None if regs[k] is None else cov)
    g = FactorGraphFusion(config, cal)
    g.restore(f.snapshot())
    for k in range(50, 90):
        s = g.update(int(times[k]), regs[k], None if regs[k] is None else cov)
        assert np.array_equal(s.readout_T_world_cam, ref[k].readout_T_world_cam)


@pytest.mark.parametrize("alpha", [0.0, -0.1, 1.5])
def test_smoothing_must_be_in_zero_one(alpha):
    with pytest.raises(ConfigError, match="revision_readout_position_smoothing"):
        FusionConfig(revision_readout_position_smoothing=alpha).validate()
