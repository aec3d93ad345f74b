"""Recordings named by a string, loaded once per worker process.

Jobs carry recordings as strings so they stay JSON-able and hashable: a path
(anything ``open_recording`` reads), ``REC::MAP`` for a recording with its
contour map (PLY), or ``sim:<scenario>`` for a simulated one with its map
(generated on demand by :mod:`evpose.eval.scenarios` and cached on disk).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from evpose.core.contour_map import ContourMap
from evpose.core.recording import Recording

SIM_PREFIX = "sim:"
MAP_SEPARATOR = "::"


def label(spec: str) -> str:
    """Short name of a recording spec for tables (scenario name or file stem)."""
    if spec.startswith(SIM_PREFIX):
        return spec[len(SIM_PREFIX) :]
    rec = spec.split(MAP_SEPARATOR)[0]
    return Path(rec).stem or rec


@lru_cache(maxsize=4)
def load_recording(spec: str) -> Recording:
    """The recording a spec names (cached per process: a sweep reuses it across configurations)."""
    if spec.startswith(SIM_PREFIX):
        from evpose.eval.scenarios import scenario_recording

        return scenario_recording(spec[len(SIM_PREFIX) :]).recording
    from evpose.io.open import open_recording

    return open_recording(Path(spec.split(MAP_SEPARATOR)[0]))


@lru_cache(maxsize=4)
def load_map(spec: str) -> ContourMap:
    """The contour map that goes with a spec; a plain recording path without ``::MAP`` has none."""
    from evpose.errors import ConfigError

    if spec.startswith(SIM_PREFIX):
        from evpose.eval.scenarios import scenario_recording

        return scenario_recording(spec[len(SIM_PREFIX) :]).contour_map
    rec, sep, map_path = spec.partition(MAP_SEPARATOR)
    if not sep:
        raise ConfigError(f"recording {rec!r} needs a contour map for tracking: pass it as {rec}{MAP_SEPARATOR}MAP.ply")
    from evpose.io.map_ply import read_contour_map

    return read_contour_map(Path(map_path))
