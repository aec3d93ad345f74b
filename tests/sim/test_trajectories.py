"""Flight paths: speed classes, the descent onto the pad, orientation, smoothness."""

import numpy as np
import pytest

from evpose.sim.scenarios import SCENARIOS
from evpose.sim.scene_library import ROOM
from evpose.sim.trajectories import RigTrajectory


def _speeds(name, seconds=6.0):
    traj = RigTrajectory(SCENARIOS[name].trajectory, seconds)
    t = np.linspace(0.0, seconds, 601)
    return traj, t, np.linalg.norm(traj.body_velocity(t), axis=1)


@pytest.mark.parametrize("name, lo, hi", [("landing_slow", 0.0, 2.0), ("landing", 2.0, 4.0), ("landing_fast", 4.0, 99.0)])
def test_landing_speed_variants_fall_in_the_ev_pose_speed_classes(name, lo, hi):
    _, _, v = _speeds(name)
    assert lo < np.mean(v) < hi


def test_spiral_descends_onto_the_pad_looking_down():
    traj, t, _ = _speeds("landing", 8.0)
    p = traj.body_position(t)
    assert np.linalg.norm(p[-1, :2]) < 0.05
    assert p[0, 2] > p[-1, 2] + 2.0
    z_cam = traj.camera_rotation(t).apply([0.0, 0.0, 1.0])
    assert np.all(z_cam[:, 2] < -0.9)


def test_rotation_variant_yaws_faster_than_30_deg_per_s():
    traj = RigTrajectory(SCENARIOS["landing_rotation"].trajectory, 4.0)
    w = traj.body_rates(np.linspace(0, 4, 401))
    assert np.rad2deg(np.abs(w[:, 2])).mean() > 30


def test_position_is_twice_differentiable():
    traj, t, _ = _speeds("landing", 6.0)
    eps = 1e-7
    knots = traj._spline.x[1:-1]
    left = traj.body_acceleration(knots - eps)
    right = traj.body_acceleration(knots + eps)
    assert np.abs(left - right).max() < 1e-3


def test_room_loop_stays_inside_the_room():
    traj = RigTrajectory(SCENARIOS["indoor"].trajectory, 10.0)
    p = traj.body_position(np.linspace(0, 10, 501))
    X, Y, Z = ROOM
    assert np.all(np.abs(p[:, 0]) < X - 1.5) and np.all(np.abs(p[:, 1]) < Y - 1.5)
    assert np.all((p[:, 2] > 0.5) & (p[:, 2] < Z - 0.5))
