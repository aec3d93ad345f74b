"""Simulated recordings + contour maps for benchmarks and sweeps, generated on demand and cached on disk.

A cached scenario is two files named by a hash of its simulation settings: the
recording as evpose HDF5 and the contour map (built from the simulator's raw
cloud) as PLY. Both are written atomically, so a crash never leaves a half file
that a later run would trust; two workers racing on the same scenario both
write complete files and the second rename wins (identical content, since the
simulator and map builder are deterministic).
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

from evpose.core.contour_map import ContourMap
from evpose.core.recording import Recording

CACHE_ENV = "EVPOSE_CACHE"
"""Environment variable overriding the default cache folder (``~/.cache/evpose``)."""


def default_cache_dir() -> Path:
    return Path(os.environ.get(CACHE_ENV, Path.home() / ".cache" / "evpose")) / "scenarios"


@dataclass(frozen=True)
class ScenarioSpec:
    """Which simulation to run; every field enters the cache key."""

    scenario: str = "landing"
    """Name in ``evpose.sim.scenarios.SCENARIOS``."""
    seconds: float = 1.0
    """Duration, seconds."""
    width: int = 240
    """Sensor width, pixels."""
    height: int = 180
    """Sensor height, pixels."""
    seed: int = 0
    """Simulator seed."""
    cloud_density_per_m2: float = 100.0
    """Density of the raw cloud the contour map is built from, points per square metre (the simulator's default)."""

    def key(self) -> str:
        """Settings plus the source of the simulator and of the map builder: changed code never reuses old files
        (``SIMULATOR_VERSION`` alone relied on a hand bump that an edit of the simulator can forget)."""
        import evpose.mapping
        import evpose.sim
        from evpose.sim.cache import source_digest
        from evpose.sim.simulator import SIMULATOR_VERSION

        code = source_digest(Path(evpose.sim.__file__).parent, Path(evpose.mapping.__file__).parent)
        blob = json.dumps({**self.__dict__, "simulator_version": SIMULATOR_VERSION, "code": code}, sort_keys=True)
        return f"{self.scenario}-{hashlib.sha256(blob.encode()).hexdigest()[:12]}"


@dataclass
class CachedScenario:
    recording: Recording
    contour_map: ContourMap
    recording_path: Path
    map_path: Path
    generated_s: float
    """Wall time spent generating now (0 when read from the cache), seconds."""


def scenario_paths(spec: ScenarioSpec, cache_dir: str | Path | None = None) -> tuple[Path, Path]:
    folder = Path(cache_dir) if cache_dir else default_cache_dir()
    key = spec.key()
    return folder / f"{key}.h5", folder / f"{key}.map.ply"


def ensure_scenario(spec: ScenarioSpec, cache_dir: str | Path | None = None) -> tuple[Path, Path, float]:
    """Generate the scenario's recording and map unless cached; returns (recording path, map path, seconds spent)."""
    rec_path, map_path = scenario_paths(spec, cache_dir)
    if rec_path.exists() and map_path.exists():
        return rec_path, map_path, 0.0
    from evpose.io.h5 import write_recording_h5
    from evpose.io.map_ply import write_contour_map
    from evpose.mapping.build import build_contour_map
    from evpose.sim.simulator import SimulationConfig, simulate

    t0 = time.perf_counter()
    from evpose.sim.lidar import LidarConfig

    lidar = LidarConfig(density_per_m2=spec.cloud_density_per_m2)
    sim = simulate(SimulationConfig(scenario=spec.scenario, seconds=spec.seconds, resolution=(spec.width, spec.height), seed=spec.seed, lidar=lidar))
    cmap = build_contour_map(sim.cloud_points, intensity=sim.cloud_intensity)
    rec_path.parent.mkdir(parents=True, exist_ok=True)
    write_recording_h5(rec_path, sim.recording)
    write_contour_map(map_path, cmap, comment=f"evpose contour map of simulated scenario {spec.scenario}")
    return rec_path, map_path, time.perf_counter() - t0


def load_scenario(spec: ScenarioSpec, cache_dir: str | Path | None = None) -> CachedScenario:
    """The scenario's recording and contour map, from the cache (generating them first if needed)."""
    from evpose.io.h5 import read_recording_h5
    from evpose.io.map_ply import read_contour_map

    rec_path, map_path, spent = ensure_scenario(spec, cache_dir)
    return CachedScenario(read_recording_h5(rec_path), read_contour_map(map_path), rec_path, map_path, spent)


def scenario_recording(name: str, cache_dir: str | Path | None = None) -> CachedScenario:
    """A scenario by name with the default :class:`ScenarioSpec` settings (what ``sim:NAME`` means)."""
    from evpose.errors import ConfigError
    from evpose.sim.scenarios import SCENARIOS

    if name not in SCENARIOS:
        raise ConfigError(f"unknown simulated scenario {name!r} (known: {', '.join(SCENARIOS)})")
    return load_scenario(ScenarioSpec(scenario=name), cache_dir)
