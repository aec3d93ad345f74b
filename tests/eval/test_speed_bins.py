"""Ground-truth speeds and the paper's slow / moderate / fast bins."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import Trajectory
from evpose.eval.metrics import Alignment, EvalConfig, evaluate
from evpose.eval.speed_bins import SpeedBinConfig, ground_truth_speeds, speed_bins


def constant_motion(speed_m_s: float, yaw_deg_s: float, n: int = 201, dt_us: int = 5000) -> Trajectory:
    t = np.arange(n) * dt_us
    s = t / 1e6
    pos = np.column_stack([speed_m_s * s, np.zeros(n), np.zeros(n)])
    rot = Rotation.from_euler("z", (yaw_deg_s * s)[:, None], degrees=True)
    return Trajectory.from_arrays(t, pos, rot.as_quat())


def test_ground_truth_speeds_of_constant_motion_are_exact():
    _, v, w = ground_truth_speeds(constant_motion(3.0, 20.0))
    np.testing.assert_allclose(v, 3.0, atol=1e-9)
    np.testing.assert_allclose(w, 20.0, atol=1e-6)


@pytest.mark.parametrize("speed,yaw,tbin,rbin", [(1.0, 5.0, "slow", "slow"), (3.0, 20.0, "moderate", "moderate"), (6.0, 45.0, "fast", "fast")])
def test_every_pose_lands_in_the_bin_of_its_speed(speed, yaw, tbin, rbin):
    gt = constant_motion(speed, yaw)
    est = Trajectory.from_arrays(gt.t, gt.position + [0.0, 0.01, 0.0], gt.quat_xyzw)
    res = evaluate(est, gt, EvalConfig(align=Alignment.NONE))
    bins = speed_bins(res, gt)
    assert bins["translation"][tbin]["ate_m"]["n"] == len(gt)
    assert bins["translation"][tbin]["ate_m"]["mean"] == pytest.approx(0.01, abs=1e-12)
    assert bins["rotation"][rbin]["rte_m"]["n"] == len(gt) - 1
    others = [b for b in ("slow", "moderate", "fast") if b != tbin]
    assert all(bins["translation"][b]["ate_m"]["n"] == 0 for b in others)


def test_bin_edges_are_configurable_and_an_edge_value_goes_to_the_faster_bin():
    from evpose.eval.speed_bins import _bin

    np.testing.assert_array_equal(_bin(np.array([1.999, 2.0, 3.9, 4.0, 4.001]), (2.0, 4.0)), [0, 1, 1, 2, 2])
    gt = constant_motion(3.0, 0.0)
    res = evaluate(gt, gt, EvalConfig(align=Alignment.NONE))
    assert speed_bins(res, gt)["translation"]["moderate"]["ate_m"]["n"] == len(gt)
    wide = speed_bins(res, gt, SpeedBinConfig(translation_edges_m_s=(3.5, 5.0)))
    assert wide["translation"]["slow"]["ate_m"]["n"] == len(gt)
