"""``evpose simulate``: write a simulated event-camera + IMU recording with ground truth, raw cloud and true edges."""

from __future__ import annotations

import dataclasses
import os
import re
from pathlib import Path

from evpose.errors import ConfigError, InputError


def parse_resolution(text: str) -> tuple[int, int]:
    """``"346x260"`` -> (346, 260); raises ConfigError for anything else."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", str(text))
    if not m:
        raise ConfigError(f"resolution must look like WIDTHxHEIGHT (e.g. 346x260), got {text!r}")
    return int(m.group(1)), int(m.group(2))


def _check_writable(out: Path) -> None:
    """Fail before hours of simulation if the output cannot be written."""
    parent = out.parent if str(out.parent) else Path(".")
    probe = parent
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if not probe.is_dir() or not os.access(probe, os.W_OK):
        raise InputError(out, "output folder is not writable")
    if out.suffix == ".h5" and out.is_dir():
        raise InputError(out, "output is an existing folder, expected an .h5 file path")
    if out.suffix != ".h5" and out.exists() and not out.is_dir():
        raise InputError(out, "output exists and is not a folder (give a path ending in .h5 for HDF5)")
    if out.suffix != ".h5":
        from evpose.io.ecd import check_ecd_target

        check_ecd_target(out)


def main(
    scenario: str,
    out: Path,
    seconds: float = 2.0,
    resolution: str = "346x260",
    seed: int = 0,
    flight: int = 0,
    distortion: bool = False,
    rotated_extrinsic: bool = False,
    noise_free: bool = False,
    no_cloud: bool = False,
    cloud_density: float = 100.0,
    range_noise: float = 0.005,
) -> int:
    """Simulate SCENARIO and write it to OUT (.h5 -> evpose HDF5, otherwise an ECD text folder).

    Next to OUT go <stem>_cloud.ply (raw LiDAR-like cloud, grey = albedo) and
    <stem>_edges.npz (true scene edges). Scenarios: landing, landing_slow,
    landing_fast, landing_rotation, indoor, landing_hdr, landing_flicker,
    landing_dynamic, landing_noisy, landing_texture.

    Args:
        scenario: Scenario name.
        out: Output recording path.
        seconds: Duration in seconds.
        resolution: Sensor size WIDTHxHEIGHT (240x180, 346x260, 640x480, 1280x720 or any within 16..4096).
        seed: Seed of every random draw; same seed, same bytes.
        flight: Which flight of the scenario: 0 its own path; N > 0 another path of the same kind and speed class
            (the spiral turned about the pad, other legs, descent and oscillation phases), independent of the seed.
        distortion: Give the lens radial-tangential distortion.
        rotated_extrinsic: Use a non-identity camera-IMU extrinsic.
        noise_free: No sensor noise (threshold spread, background activity, IMU noise).
        no_cloud: Do not write the raw cloud and edges.
        cloud_density: Raw cloud density, points per square metre of surface.
        range_noise: Raw cloud range noise (standard deviation along the surface normal), metres.
    """
    from evpose.sim import Extrinsic, SimulationConfig, simulate
    from evpose.sim.lidar import LidarConfig
    from evpose.sim.outputs import write_simulation
    from evpose.sim.simulator import validate_config

    if not (cloud_density > 0 and range_noise >= 0):
        raise ConfigError(f"cloud density must be positive and range noise non-negative, got {cloud_density} and {range_noise}")
    # The config's slider range: --cloud-density 1e12 ended in a MemoryError traceback (22 PiB of points).
    limits = {f.name: f.metadata for f in dataclasses.fields(LidarConfig)}
    for flag, value, meta in (("--cloud-density", cloud_density, limits["density_per_m2"]), ("--range-noise", range_noise, limits["range_noise_m"])):
        if not meta["min"] <= value <= meta["max"]:
            raise ConfigError(f"{flag} must be within {meta['min']:g}..{meta['max']:g} {meta['unit']}, got {value:g}")

    cfg = SimulationConfig(
        scenario=scenario,
        seconds=float(seconds),
        resolution=parse_resolution(resolution),
        seed=int(seed),
        flight=int(flight),
        distortion=distortion,
        extrinsic=Extrinsic.ROTATED if rotated_extrinsic else Extrinsic.IDENTITY,
        noise_free=noise_free,
        lidar=LidarConfig(density_per_m2=float(cloud_density), range_noise_m=float(range_noise)),
    )
    validate_config(cfg)
    out = Path(out)
    _check_writable(out)
    result = simulate(cfg)
    paths = write_simulation(result, out, cloud=not no_cloud)
    s = result.stats
    n = len(result.recording.events)
    print(
        f"{scenario}: {n} events ({n / cfg.seconds / 1e6:.3f} Mev/s) in {cfg.seconds:g} s at {cfg.resolution[0]}x{cfg.resolution[1]}, "
        f"{s['renders']} renders, {s['wall_s']:.1f} s wall ({cfg.seconds / s['wall_s']:.3f} simulated s per wall s)"
    )
    for kind, p in paths.items():
        print(f"  {kind}: {p}")
    return 0
