"""Other flights of a scenario: the same kind of path and speed, another route, flight 0 unchanged."""

import numpy as np
import pytest

from evpose.errors import ConfigError
from evpose.sim.flight_variants import vary_flight
from evpose.sim.scenarios import SCENARIOS
from evpose.sim.scene_library import ROOM
from evpose.sim.simulator import SimulationConfig, validate_config
from evpose.sim.trajectories import RigTrajectory


def test_flight_zero_is_the_scenarios_own_path_bit_for_bit():
    cfg = SCENARIOS["landing"].trajectory
    assert vary_flight(cfg, 0) is cfg
    t = np.linspace(0.0, 2.0, 201)
    a = RigTrajectory(cfg, 2.0).camera_poses(t)
    b = RigTrajectory(vary_flight(cfg, 0), 2.0).camera_poses(t)
    assert np.array_equal(a, b)


def test_flight_is_deterministic_and_each_flight_differs():
    cfg = SCENARIOS["landing"].trajectory
    assert vary_flight(cfg, 7) == vary_flight(cfg, 7)
    headings = {round(vary_flight(cfg, n).heading_deg, 6) for n in range(1, 9)}
    assert len(headings) == 8


@pytest.mark.parametrize("flight", [1, 2, 3, 4, 5, 6])
def test_landing_flights_keep_speed_class_and_end_over_the_pad_looking_down(flight):
    cfg = vary_flight(SCENARIOS["landing"].trajectory, flight)
    traj = RigTrajectory(cfg, 4.0)
    t = np.linspace(0.0, 4.0, 401)
    p = traj.body_position(t)
    assert np.linalg.norm(p[-1, :2]) < 0.05
    assert p[0, 2] > p[-1, 2] + 1.0
    assert 2.0 < np.linalg.norm(traj.body_velocity(t), axis=1).mean() < 4.0
    assert np.all(traj.camera_rotation(t).apply([0.0, 0.0, 1.0])[:, 2] < -0.9)
    # Another route: the first second's ground track leaves the pad in another direction than flight 0's.
    nominal = RigTrajectory(SCENARIOS["landing"].trajectory, 4.0).body_position(t)
    assert np.abs(p[:100, :2] - nominal[:100, :2]).max() > 0.5


@pytest.mark.parametrize("flight", range(1, 13))
def test_room_flights_stay_inside_the_room(flight):
    traj = RigTrajectory(vary_flight(SCENARIOS["indoor"].trajectory, flight), 10.0)
    p = traj.body_position(np.linspace(0, 10, 501))
    X, Y, Z = ROOM
    assert np.all(np.abs(p[:, 0]) < X - 1.5) and np.all(np.abs(p[:, 1]) < Y - 1.5)
    assert np.all((p[:, 2] > 0.5) & (p[:, 2] < Z - 0.5))


def test_negative_flight_is_a_one_line_config_error():
    with pytest.raises(ConfigError, match="flight must be non-negative"):
        validate_config(SimulationConfig(flight=-1))


def _lowest_over_structure(p: np.ndarray) -> float:
    """Lowest height of ``p`` above a box top within 1 m of the box's footprint, metres."""
    from evpose.sim import scene_library as lib

    lowest = np.inf
    for x, y, sx, sy, h, _, yaw in lib._BUILDINGS + lib._CRATES + lib._CLUTTER:
        c, s = np.cos(yaw), np.sin(yaw)
        d = p[:, :2] - (x, y)
        u, v = d[:, 0] * c + d[:, 1] * s, -d[:, 0] * s + d[:, 1] * c
        near = (np.abs(u) < sx / 2 + 1.0) & (np.abs(v) < sy / 2 + 1.0)
        if near.any():
            lowest = min(lowest, float((p[near, 2] - h).min()))
    return lowest


@pytest.mark.parametrize("seconds", [2.0, 4.0])
def test_landing_flights_clear_every_building_and_crate(seconds):
    t = np.linspace(0.0, seconds, 400)
    for flight in range(25):
        traj = RigTrajectory(vary_flight(SCENARIOS["landing"].trajectory, flight), seconds)
        assert _lowest_over_structure(traj.body_position(t)) > 0.8, flight
