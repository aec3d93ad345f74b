"""Ray-cast rendering: adaptive supersampling, exact geometry, and polarity from brightness constancy."""

import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.sim import render as render_mod
from evpose.sim.esim import EsimConfig, EventGenerator
from evpose.sim.render import RenderConfig, Renderer
from evpose.sim.scene_library import SceneOptions, landing_scene
from evpose.sim.scenes import MeshPart, Scene, quad_part

_DOWN = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])


def _pose(x, y, z):
    T = np.eye(4)
    T[:3, :3] = _DOWN
    T[:3, 3] = (x, y, z)
    return T


def _square_scene():
    ground = quad_part([(-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0)], 0.1)
    square = quad_part([(-0.5, -0.5, 0.01), (0.5, -0.5, 0.01), (0.5, 0.5, 0.01), (-0.5, 0.5, 0.01)], 0.9)
    return Scene("square", MeshPart.concatenate([ground, square]), np.zeros((0, 2, 3)))


def test_adaptive_supersampling_equals_full_supersampling(monkeypatch):
    cal = CameraCalibration(64, 48, 50.0, 50.0, 31.5, 23.5)
    scene = landing_scene(SceneOptions())
    r = Renderer(scene, cal, RenderConfig(supersampling=3))
    T = _pose(0.4, 0.3, 3.0)
    adaptive = r.render(T, 0.0).group_images
    monkeypatch.setattr(render_mod, "_needs_supersampling", lambda img, tex, band=None, rel_tol=1e-6: np.ones(img.shape[1:], bool))
    full = r.render(T, 0.0).group_images
    assert np.max(np.abs(adaptive - full)) < 1e-5


def test_square_edge_lands_on_its_projection():
    cal = CameraCalibration(64, 48, 50.0, 50.0, 31.5, 23.5)
    r = Renderer(_square_scene(), cal, RenderConfig(supersampling=4))
    L = r.log_image(r.render(_pose(0.0, 0.0, 2.0), 0.0), np.ones(1))
    # The square spans x in [-0.5, 0.5] m at depth 1.99 m -> columns 31.5 +- 50 * 0.5 / 1.99.
    # Box-filtered pixels: the row's brightness above the ground level measures the covered width and its centre.
    row = np.exp(L[24]) - 0.01
    lo, hi = row.min(), row.max()
    cover = (row - lo) / (hi - lo)
    width = cover.sum()
    centre = (cover * np.arange(64)).sum() / width
    assert abs(width - 2 * 50 * 0.5 / 1.99) < 0.2  # s = 4 quantises coverage to 1/4 pixel per edge
    assert abs(centre - 31.5) < 0.05


def test_edge_moving_from_bright_into_dark_gives_off_events():
    """Camera moves +x, so the bright square moves -x in the image: its right edge leaves pixels (OFF), its left edge enters (ON)."""
    cal = CameraCalibration(64, 48, 50.0, 50.0, 31.5, 23.5)
    r = Renderer(_square_scene(), cal, RenderConfig(supersampling=3))
    gen = EventGenerator(EsimConfig(c_sigma=0.0), 64, 48, np.random.default_rng(0))
    gen.reset(r.log_image(r.render(_pose(0.0, 0.0, 2.0), 0.0), np.ones(1)), 0)
    events = []
    for k in range(1, 41):  # 0.2 m in 40 steps of 0.125 px
        events.append(gen.step(r.log_image(r.render(_pose(0.005 * k, 0.0, 2.0), 0.0), np.ones(1)), 1000 * k))
    x = np.concatenate([e.x for e in events]).astype(float)
    p = np.concatenate([e.p for e in events])
    assert len(p) > 100
    right = x > 31.5
    assert np.all(p[right] == -1)
    assert np.all(p[~right] == 1)


def test_incremental_render_equals_a_fresh_render_along_a_flight():
    from evpose.sim.scenarios import SCENARIOS
    from evpose.sim.trajectories import RigTrajectory

    cal = CameraCalibration(96, 72, 70.0, 70.0, 47.5, 35.5)
    r = Renderer(landing_scene(), cal)
    traj = RigTrajectory(SCENARIOS["landing"].trajectory, 2.0)
    ts = np.arange(0.0, 0.2, 0.004)  # ~0.5 px per step at this resolution
    poses = traj.camera_poses(ts)
    out = r.render(poses[0], 0.0)
    for k in range(1, len(ts)):
        out = r.render(poses[k], ts[k], previous=out)
    fresh = r.render(poses[-1], ts[-1])
    np.testing.assert_array_equal(out.group_images, fresh.group_images)


def test_incremental_render_follows_moving_objects():
    from evpose.sim.scenarios import SCENARIOS
    from evpose.sim.trajectories import RigTrajectory

    cal = CameraCalibration(96, 72, 70.0, 70.0, 47.5, 35.5)
    r = Renderer(landing_scene(SceneOptions(dynamic=True)), cal)
    traj = RigTrajectory(SCENARIOS["landing_dynamic"].trajectory, 1.0)
    ts = np.arange(0.8, 1.0, 0.002)
    poses = traj.camera_poses(ts)
    out = r.render(poses[0], ts[0])
    for k in range(1, len(ts)):
        out = r.render(poses[k], ts[k], previous=out)
    assert out.footprint is not None and out.footprint.any()  # the fan is in view and was re-cast, not re-rendered whole
    fresh = r.render(poses[-1], ts[-1])
    np.testing.assert_array_equal(out.group_images, fresh.group_images)
