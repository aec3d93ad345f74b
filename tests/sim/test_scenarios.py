"""Every scenario runs; the condition variants create the effects they promise."""

import numpy as np
import pytest

from evpose.sim import SimulationConfig, simulate
from evpose.sim.scenarios import SCENARIOS

REQUIRED = {"landing", "landing_slow", "landing_fast", "landing_rotation", "indoor", "landing_hdr", "landing_flicker", "landing_dynamic", "landing_noisy", "landing_texture"}


def _sim(name, seconds=0.06, noise_free=True, **kw):
    return simulate(SimulationConfig(scenario=name, seconds=seconds, resolution=(64, 48), seed=0, noise_free=noise_free, **kw))


def test_all_required_scenarios_exist():
    assert REQUIRED <= set(SCENARIOS)


@pytest.mark.parametrize("name", sorted(REQUIRED))
def test_scenario_produces_a_valid_recording(name):
    rec = _sim(name, noise_free=False).recording
    rec.validate()
    assert len(rec.events) > 0
    assert rec.metadata["scenario"] == name
    assert len(rec.ground_truth) == 61 and len(rec.imu) == 31


def _render_pair(name, t0, t1, res=(96, 72)):
    """Renders of a scenario's scene from the final hover pose over the pad at two times."""
    from evpose.core.camera import CameraCalibration
    from evpose.sim.render import Renderer
    from evpose.sim.scene_library import build_scene

    sc = SCENARIOS[name]
    scene = build_scene(sc.scene, sc.options)
    cal = CameraCalibration(res[0], res[1], 0.7 * res[0], 0.7 * res[0], (res[0] - 1) / 2, (res[1] - 1) / 2)
    T = np.eye(4)
    T[:3, :3] = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
    T[:3, 3] = (0.5, -0.5, 4.0)
    r = Renderer(scene, cal)
    return scene, [r.log_image(r.render(T, t), scene.gains(t)) for t in (t0, t1)]


def test_dynamic_objects_change_the_image_of_a_still_camera():
    _, (a, b) = _render_pair("landing_dynamic", 0.0, 0.05)
    assert np.sum(np.abs(a - b) > 0.3) > 20
    _, (a, b) = _render_pair("landing", 0.0, 0.05)
    assert np.array_equal(a, b)


def test_dynamic_scenario_adds_events_but_no_map_edges():
    static = _sim("landing", 0.1)
    dynamic = _sim("landing_dynamic", 0.1)
    assert len(dynamic.recording.events) > len(static.recording.events)
    np.testing.assert_array_equal(dynamic.edges, static.edges)


def test_fine_ground_texture_varies_on_every_pixel_of_the_ground():
    _, (plain, _) = _render_pair("landing", 0.0, 0.0)
    _, (tex, _) = _render_pair("landing_texture", 0.0, 0.0)
    gy, gx = np.gradient(tex)
    assert np.median(np.hypot(gx, gy)) > 0.02
    gy, gx = np.gradient(plain)
    assert np.median(np.hypot(gx, gy)) == 0.0


def test_noisy_scenario_adds_background_events():
    quiet = _sim("landing", noise_free=False).recording.events
    noisy = _sim("landing_noisy", noise_free=False).recording.events
    # 5 Hz/pixel on 64 x 48 pixels for 0.06 s ~ 920 extra events, plus hot pixels.
    assert len(noisy) - len(quiet) > 700


def test_flicker_modulates_the_lit_objects_at_its_frequency():
    scene, (a, b) = _render_pair("landing_flicker", 0.005, 0.015)  # a quarter and three quarters of a 50 Hz period
    lit = np.abs(a - b) > 1e-6
    assert lit.sum() > 20
    np.testing.assert_allclose((a - b)[lit].max(), np.log(1.5 / 0.5), atol=0.05)  # gain 1 +- 0.5 on the crates


def test_hdr_regions_are_far_brighter_and_darker_than_the_rest():
    scene, (a, _) = _render_pair("landing_hdr", 0.0, 0.0)
    _, (plain, _) = _render_pair("landing", 0.0, 0.0)
    diff = a - plain
    assert diff.max() > np.log(10) and diff.min() < -np.log(5)  # a crate near the pad is lit 15x, another dimmed 20x


def test_hdr_light_switches_off():
    from evpose.sim.scene_library import build_scene

    sc = SCENARIOS["landing_hdr"]
    scene = build_scene(sc.scene, sc.options)
    g = np.array([scene.gains(t) for t in (0.5, 1.2)])
    assert g[0, 1] / g[1, 1] > 40  # the bright building's light goes from 15x to 0.3x
    assert g[0, 2] < 0.1  # and one building stays 20x darker
