"""End-to-end simulation: events on the true edges, polarity, sorting, determinism, metadata, bad input."""

import hashlib

import numpy as np
import pytest

from evpose.errors import ConfigError
from evpose.sim import Extrinsic, SimulationConfig, simulate
from evpose.sim.outputs import write_simulation
from evpose.sim.render import Renderer


@pytest.fixture(scope="module")
def clean_landing():
    return simulate(SimulationConfig(scenario="landing", seconds=0.25, resolution=(240, 180), seed=1, noise_free=True))


def _distance_to_segments(uv, a, b):
    ab = b - a
    t = np.clip(((uv - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-12), 0.0, 1.0)
    return np.min(np.linalg.norm(a + t[:, None] * ab - uv, axis=1))


def test_noise_free_events_lie_on_projected_true_edges(clean_landing):
    rec = clean_landing.recording
    ev, cal = rec.events, rec.calibration
    idx = np.sort(np.random.default_rng(0).choice(len(ev), 2000, replace=False))
    poses = rec.ground_truth.interpolate(ev.t[idx]).matrices()
    segs = np.concatenate([clean_landing.edges, clean_landing.albedo_edges])
    d = []
    for k, i in enumerate(idx):
        R, o = poses[k, :3, :3], poses[k, :3, 3]
        A, B = (segs[:, 0] - o) @ R, (segs[:, 1] - o) @ R
        front = (A[:, 2] > 0.05) & (B[:, 2] > 0.05)
        d.append(_distance_to_segments(np.array([ev.x[i], ev.y[i]], float), cal.project(A[front]), cal.project(B[front])))
    d = np.array(d)
    assert np.median(d) < 0.5
    assert np.mean(d < 1.5) > 0.95


def test_polarity_agrees_with_brightness_constancy(clean_landing):
    """dL/dt = -grad(L) . v: an edge moving from bright into dark gives OFF events, dark into bright ON."""
    import cv2

    rec = clean_landing.recording
    cal, scene = rec.calibration, clean_landing.scene
    r = Renderer(scene, cal)
    agree = []
    for tc in (0.08, 0.16):
        ev = rec.events.time_window(int(tc * 1e6) - 1000, int(tc * 1e6) + 1000)
        T0, T1 = clean_landing.trajectory.camera_poses(np.array([tc, tc + 1e-3]))
        out = r.render(T0, tc)
        L = cv2.GaussianBlur(r.log_image(out, scene.gains(tc)), (0, 0), 1.0)
        gy, gx = np.gradient(L)
        uv0 = cal.project((out.points - T0[:3, 3]) @ T0[:3, :3])
        uv1 = cal.project((out.points - T1[:3, 3]) @ T1[:3, :3])
        v = ((uv1 - uv0) / 1e-3).reshape(cal.height, cal.width, 2)  # motion field from the ground truth, px/s
        dLdt = -(gx * v[..., 0] + gy * v[..., 1])
        agree.append(np.sign(dLdt[ev.y, ev.x]) == ev.p)
    agree = np.concatenate(agree)
    assert agree.size > 200
    assert agree.mean() > 0.97


def test_recording_is_complete_and_sorted(clean_landing):
    rec = clean_landing.recording
    rec.validate()
    assert np.all(np.diff(rec.events.t) >= 0)
    assert rec.events.t[0] >= 0 and rec.events.t[-1] <= 250_000
    assert rec.ground_truth.t[0] == 0 and np.median(np.diff(rec.ground_truth.t)) == 1000
    assert rec.imu.rate_hz == 500
    assert rec.metadata["scenario"] == "landing" and rec.metadata["seed"] == 1
    assert (rec.metadata["width"], rec.metadata["height"]) == (240, 180)
    assert set(np.unique(rec.events.p)) == {-1, 1}


def test_same_seed_gives_the_same_bytes(tmp_path):
    cfg = SimulationConfig(scenario="landing_noisy", seconds=0.08, resolution=(64, 48), seed=7, extrinsic=Extrinsic.ROTATED)
    digests = []
    for k in range(2):
        paths = write_simulation(simulate(cfg), tmp_path / f"run{k}" / "rec.h5")
        digests.append([hashlib.sha256(p.read_bytes()).hexdigest() for p in paths.values()])
    assert digests[0] == digests[1]
    other = simulate(SimulationConfig(scenario="landing_noisy", seconds=0.08, resolution=(64, 48), seed=8))
    first = simulate(cfg)
    assert len(other.recording.events) != len(first.recording.events) or not np.array_equal(other.recording.events.x, first.recording.events.x)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(scenario="moon_landing"), "unknown scenario"),
        (dict(resolution=(0, 180)), "impossible resolution"),
        (dict(resolution=(100000, 10)), "impossible resolution"),
        (dict(seconds=-1.0), "duration must be positive"),
    ],
)
def test_bad_settings_raise_one_line_config_errors(kwargs, message):
    with pytest.raises(ConfigError, match=message) as exc:
        simulate(SimulationConfig(**kwargs))
    assert "\n" not in str(exc.value)


def test_distorted_camera_events_lie_on_distorted_projections_of_edges():
    res = simulate(SimulationConfig(scenario="landing", seconds=0.05, resolution=(128, 96), seed=2, noise_free=True, distortion=True))
    rec = res.recording
    assert rec.calibration.model.value == "radtan"
    ev, cal = rec.events, rec.calibration
    idx = np.sort(np.random.default_rng(0).choice(len(ev), 500, replace=False))
    poses = rec.ground_truth.interpolate(ev.t[idx]).matrices()
    segs = np.concatenate([res.edges, res.albedo_edges])
    # Distortion bends straight edges: sample each segment densely and project the samples.
    pts = segs[:, 0, None, :] + np.linspace(0, 1, 200)[None, :, None] * (segs[:, 1] - segs[:, 0])[:, None, :]
    d = []
    for k, i in enumerate(idx):
        R, o = poses[k, :3, :3], poses[k, :3, 3]
        pc = (pts.reshape(-1, 3) - o) @ R
        uv = cal.project(pc[pc[:, 2] > 0.05])
        d.append(np.min(np.linalg.norm(uv - [ev.x[i], ev.y[i]], axis=1)))
    assert np.median(d) < 0.5
