"""The simulator's entry point: scenario + settings -> recording with ground truth, raw cloud and true edges.

Rendering follows ESIM's adaptive rule: after each render the next render time
is chosen so that no pixel's image position moves more than
``max_pixel_step`` pixels (estimated from the rendered surface points and the
motion of the camera and of any moving object). Light-group gain changes
(flicker, switching) are resolved by cheap sub-steps between renders that
re-weight the per-group images without casting rays, so that no pixel's log
intensity changes by more than ``max_log_step`` from gains in one sub-step.
"""

from __future__ import annotations

import enum
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from evpose.core.camera import CameraCalibration, DistortionModel
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.errors import ConfigError
from evpose.sim.esim import EsimConfig, EventGenerator
from evpose.sim.flight_variants import vary_flight
from evpose.sim.imu_model import ImuConfig, ImuTruth, simulate_imu
from evpose.sim.lidar import LidarConfig, sample_cloud
from evpose.sim.noise import NoiseConfig, noise_events
from evpose.sim.render import RenderConfig, Renderer, cv2_dilate
from evpose.sim.scenarios import SCENARIOS
from evpose.sim.scene_library import build_scene
from evpose.sim.scenes import Scene
from evpose.sim.trajectories import RigTrajectory, TrajectoryConfig

SIMULATOR_VERSION = 1
STANDARD_RESOLUTIONS = ((240, 180), (346, 260), (640, 480), (1280, 720))
_FLOW_PROBE_S = 1e-3  # finite-difference interval for image-motion estimates
_FLOW_STRIDE = 2  # probe every 2nd pixel in x and y


class Extrinsic(str, enum.Enum):
    """Camera-IMU extrinsic of the simulated rig."""

    IDENTITY = "identity"
    ROTATED = "rotated"
    """IMU rotated 90 deg about the camera's optical axis and tilted 2 deg, offset by a few centimetres."""


def _rotated_extrinsic() -> np.ndarray:
    from scipy.spatial.transform import Rotation

    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("zx", [90.0, 2.0], degrees=True).as_matrix()
    T[:3, 3] = (0.03, -0.015, 0.02)
    return T


@dataclass(frozen=True)
class SimulationConfig:
    """One simulation run. ``None`` sensor/flight sections take the scenario's defaults."""

    scenario: str = "landing"
    """Name in :data:`evpose.sim.scenarios.SCENARIOS`."""
    seconds: float = field(default=2.0, metadata={"min": 0.05, "max": 60.0, "unit": "s"})
    """Duration, seconds."""
    resolution: tuple[int, int] = (346, 260)
    """Sensor width and height, pixels."""
    seed: int = 0
    """Seed of every random draw (thresholds, noise, IMU, cloud)."""
    flight: int = 0
    """Which flight of the scenario: 0 its own path, N > 0 another path of the same kind and speed
    (:func:`evpose.sim.flight_variants.vary_flight`), independent of ``seed``."""
    hfov_deg: float = 70.0
    """Horizontal field of view of the ideal pinhole, degrees."""
    distortion: bool = False
    """Give the lens radial-tangential distortion (k1 = -0.15)."""
    extrinsic: Extrinsic = Extrinsic.IDENTITY
    """Camera-IMU extrinsic."""
    noise_free: bool = False
    """No background noise, no hot pixels, no threshold spread, ideal IMU (for tests)."""
    gt_rate_hz: int = 1000
    """Ground-truth pose rate, Hz (>= 200)."""
    max_pixel_step: float = field(default=0.5, metadata={"min": 0.05, "max": 2.0, "unit": "px"})
    """Largest image motion of any pixel between two renders, pixels (ESIM's rule)."""
    max_log_step: float = 0.05
    """Largest log-intensity change from light gains in one sub-step, log units."""
    min_render_step_us: int = 20
    """Smallest render interval, microseconds."""
    max_render_step_us: int = 10_000
    """Largest render interval, microseconds."""
    incremental_render: bool = True
    """Re-cast only pixels near the previous frame's discontinuities (exact for static untextured regions)."""
    render: RenderConfig = field(default_factory=RenderConfig)
    esim: EsimConfig | None = None
    noise: NoiseConfig | None = None
    imu: ImuConfig = field(default_factory=ImuConfig)
    lidar: LidarConfig = field(default_factory=LidarConfig)
    trajectory: TrajectoryConfig | None = None


@dataclass
class SimulationResult:
    """A simulated recording plus everything the tests and map building need."""

    recording: Recording
    cloud_points: np.ndarray
    """(N, 3) LiDAR-like raw cloud of the static scene, world frame, metres."""
    cloud_intensity: np.ndarray
    """(N,) albedo at each cloud point, 0..1."""
    edges: np.ndarray
    """(M, 2, 3) true static edge segments (creases, contact lines, pad border), world frame, metres."""
    albedo_edges: np.ndarray
    """(K, 2, 3) painted boundaries (pad marker), world frame, metres."""
    scene: Scene
    trajectory: RigTrajectory
    imu_truth: ImuTruth
    stats: dict
    """Renders, sub-steps, wall time per stage (seconds)."""
    files: dict = field(default_factory=dict)
    """Paths written by :func:`evpose.sim.outputs.write_simulation` (``recording``, ``cloud``, ``edges``), if any."""


def make_calibration(cfg: SimulationConfig, T_cam_imu: np.ndarray) -> CameraCalibration:
    w, h = cfg.resolution
    f = (w / 2.0) / np.tan(np.deg2rad(cfg.hfov_deg) / 2.0)
    model, dist = (DistortionModel.RADTAN, (-0.15, 0.04, 0.0005, -0.0003, 0.0)) if cfg.distortion else (DistortionModel.NONE, ())
    return CameraCalibration(w, h, f, f, (w - 1) / 2.0, (h - 1) / 2.0, model, dist, T_cam_imu)


def validate_config(cfg: SimulationConfig) -> None:
    """Raise :class:`ConfigError` (one line) for an unknown scenario or impossible settings."""
    if cfg.scenario not in SCENARIOS:
        raise ConfigError(f"unknown scenario {cfg.scenario!r}; choose one of: {', '.join(SCENARIOS)}")
    try:
        w, h = (int(v) for v in cfg.resolution)
    except (TypeError, ValueError):
        raise ConfigError(f"resolution must be two integers WxH, got {cfg.resolution!r}") from None
    if not (16 <= w <= 4096 and 16 <= h <= 4096):
        raise ConfigError(f"impossible resolution {w}x{h}: width and height must be within 16..4096 pixels")
    if not np.isfinite(cfg.seconds) or cfg.seconds <= 0:
        raise ConfigError(f"duration must be positive, got {cfg.seconds} s")
    if cfg.seconds > 600:
        raise ConfigError(f"duration {cfg.seconds} s is longer than the 600 s the simulator supports")
    if not (1.0 <= cfg.hfov_deg <= 170.0):
        raise ConfigError(f"horizontal field of view {cfg.hfov_deg} deg is outside 1..170")
    if cfg.gt_rate_hz < 200 or 1_000_000 % int(cfg.gt_rate_hz):
        raise ConfigError(f"ground-truth rate {cfg.gt_rate_hz} Hz must be >= 200 and divide 1 s into whole microseconds")
    if not (200 <= cfg.imu.rate_hz <= 1000) or 1_000_000 % int(cfg.imu.rate_hz):
        raise ConfigError(f"IMU rate {cfg.imu.rate_hz} Hz must be within 200..1000 and divide 1 s into whole microseconds")
    if cfg.seed < 0:
        raise ConfigError(f"seed must be non-negative, got {cfg.seed}")
    if cfg.flight < 0:
        raise ConfigError(f"flight must be non-negative, got {cfg.flight}")


def _image_speed(renderer: Renderer, out, traj: RigTrajectory, scene: Scene, t_s: float, T_wc: np.ndarray) -> float:
    """Largest image speed (px/s) of the surface points seen at ``t_s`` near intensity discontinuities.

    ESIM bounds the motion of every pixel; only pixels on or next to an
    intensity discontinuity can change (uniform regions stay uniform), so
    bounding those is the same rule at a fraction of the cost.
    """
    cal = renderer.calibration
    # Only pixels near intensity discontinuities can emit events, and only there are the hit points fresh.
    near = cv2_dilate(out.mark, 2) & out.fresh
    if not near.any():
        near = out.fresh
    near[1::_FLOW_STRIDE, :] = False
    near[:, 1::_FLOW_STRIDE] = False
    idx = np.flatnonzero(near.ravel())
    face = out.face[idx]
    hit = face >= 0
    idx, face = idx[hit], face[hit]
    if idx.size == 0:
        return 0.0
    P0 = out.points[idx]
    P1 = P0.copy()
    owner = out.face_owner[face]
    for k, obj in enumerate(scene.dynamic):
        sel = owner == k
        if sel.any():
            M = obj.pose(t_s + _FLOW_PROBE_S) @ np.linalg.inv(obj.pose(t_s))
            P1[sel] = P0[sel] @ M[:3, :3].T + M[:3, 3]
    T_next = traj.camera_poses(t_s + _FLOW_PROBE_S)[0]
    uv0 = cal.project((P0 - T_wc[:3, 3]) @ T_wc[:3, :3])
    uv1 = cal.project((P1 - T_next[:3, 3]) @ T_next[:3, :3])
    d = np.linalg.norm(uv1 - uv0, axis=1)
    d = d[np.isfinite(d)]
    return float(d.max() / _FLOW_PROBE_S) if d.size else 0.0


def _gain_substeps(scene: Scene, t0_s: float, t1_s: float, max_log_step: float) -> int:
    """Sub-steps needed so gains change log intensity by at most ``max_log_step`` per sub-step."""
    if scene.group_gain is None:
        return 1
    ts = np.linspace(t0_s, t1_s, 33)
    g = np.log(np.maximum(np.stack([scene.gains(t) for t in ts]), 1e-9))
    variation = np.abs(np.diff(g, axis=0)).sum(axis=0).max()
    return max(1, int(np.ceil(variation / max_log_step)))


def _render_events(cfg: SimulationConfig, scene: Scene, traj: RigTrajectory, cal: CameraCalibration, esim: EsimConfig, rng, stats) -> EventArray:
    renderer = Renderer(scene, cal, cfg.render)
    gen = EventGenerator(esim, cal.width, cal.height, rng)
    t_end = int(round(cfg.seconds * 1e6))
    t = 0
    T_wc = traj.camera_poses(0.0)[0]
    out = renderer.render(T_wc, 0.0)
    gen.reset(renderer.log_image(out, scene.gains(0.0)), 0)
    chunks = []
    n_render, n_sub = 1, 0
    t_render = t_esim = 0.0
    while t < t_end:
        speed = _image_speed(renderer, out, traj, scene, t * 1e-6, T_wc)
        dt = cfg.max_render_step_us if speed <= 0 else int(cfg.max_pixel_step / speed * 1e6)
        dt = int(np.clip(dt, cfg.min_render_step_us, cfg.max_render_step_us))
        t_next = min(t + dt, t_end)
        T_next = traj.camera_poses(t_next * 1e-6)[0]
        c0 = time.perf_counter()
        nxt = renderer.render(T_next, t_next * 1e-6, previous=out if cfg.incremental_render else None)
        c1 = time.perf_counter()
        n = _gain_substeps(scene, t * 1e-6, t_next * 1e-6, cfg.max_log_step)
        for k in range(1, n + 1):
            tk = t + (t_next - t) * k // n
            if k == n:
                img = nxt.group_images
            else:
                a = k / n
                img = (1 - a) * out.group_images + a * nxt.group_images
            lin = np.tensordot(scene.gains(tk * 1e-6), img.astype(np.float64), axes=1)
            ev = gen.step(np.log(lin + cfg.render.log_eps), tk)
            if len(ev):
                chunks.append(ev)
        c2 = time.perf_counter()
        t_render += c1 - c0
        t_esim += c2 - c1
        n_render += 1
        n_sub += n
        t, T_wc, out = t_next, T_next, nxt
    stats.update(renders=n_render, esim_steps=n_sub, render_s=t_render, esim_s=t_esim, rays=renderer.stats["rays"])
    return EventArray.concatenate(chunks)


def _jsonable(obj):
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, enum.Enum):
        return obj.value
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    return obj


_FLIGHT_FIELDS = ("heading_deg", "oscillation_phase_deg")


def _without_zero(d: dict, keys: tuple[str, ...]) -> dict:
    """``d`` without the ``keys`` whose value is 0: a recording of a scenario's own flight keeps the metadata, and so
    the bytes, it had before flights existed (``scripts/make_demo_data.py --check``)."""
    return {k: v for k, v in d.items() if not (k in keys and not v)}


def simulate(config: SimulationConfig) -> SimulationResult:
    """Simulate ``config``: events, IMU, ground truth, calibration, raw cloud and true edges."""
    validate_config(config)
    wall0 = time.perf_counter()
    sc = SCENARIOS[config.scenario]
    esim = config.esim or sc.esim
    noise = config.noise or sc.noise
    traj_cfg = vary_flight(config.trajectory or sc.trajectory, int(config.flight))
    imu_cfg = config.imu
    if config.noise_free:
        from dataclasses import replace

        esim = replace(esim, c_sigma=0.0)
        imu_cfg = replace(imu_cfg, noise_free=True)
    seeds = np.random.SeedSequence(int(config.seed)).spawn(4)
    rng_thr, rng_noise, rng_imu, rng_cloud = (np.random.default_rng(s) for s in seeds)

    T_cam_imu = _rotated_extrinsic() if Extrinsic(config.extrinsic) is Extrinsic.ROTATED else np.eye(4)
    cal = make_calibration(config, T_cam_imu)
    scene = build_scene(sc.scene, sc.options)
    traj = RigTrajectory(traj_cfg, config.seconds, T_cam_imu)
    stats: dict = {}

    events = _render_events(config, scene, traj, cal, esim, rng_thr, stats)
    t_end = int(round(config.seconds * 1e6))
    if not config.noise_free:
        nz = noise_events(noise, cal.width, cal.height, 0, t_end, rng_noise)
        if len(nz):
            merged = EventArray.concatenate([events, nz])
            order = np.argsort(merged.t, kind="stable")
            events = merged[order]
            stats["noise_events"] = len(nz)
    imu = simulate_imu(traj, imu_cfg, 0, t_end, rng_imu)
    gt_t = np.arange(0, t_end + 1, 1_000_000 // int(config.gt_rate_hz), dtype=np.int64)
    gt = traj.ground_truth(gt_t)
    c0 = time.perf_counter()
    cloud, intensity = sample_cloud(scene, config.lidar, rng_cloud)
    stats["cloud_s"] = time.perf_counter() - c0
    stats["wall_s"] = time.perf_counter() - wall0
    stats["events"] = len(events)

    metadata = {
        "source_format": "evpose-sim",
        "simulator_version": SIMULATOR_VERSION,
        "scenario": config.scenario,
        "scenario_description": sc.description,
        "seed": int(config.seed),
        "seconds": float(config.seconds),
        "width": cal.width,
        "height": cal.height,
        "config": _jsonable(_without_zero(asdict(config), ("flight",))),
        "effective": _jsonable({"esim": asdict(esim), "noise": asdict(noise), "trajectory": _without_zero(asdict(traj_cfg), _FLIGHT_FIELDS), "imu": asdict(imu_cfg), "scene_options": asdict(sc.options)}),
    }
    rec = Recording(events=events, imu=imu.samples, ground_truth=gt, calibration=cal, metadata=metadata)
    return SimulationResult(rec, cloud, intensity, scene.edges.copy(), scene.albedo_edges.copy(), scene, traj, imu, stats)
