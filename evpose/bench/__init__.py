"""Micro-benchmarks, one module per area, collected by ``evpose bench``.

Each area module defines ``BENCHMARKS: dict[str, Callable[[BenchContext], dict]]``.
A benchmark returns a flat dict of measured figures (floats/ints/strings) with
units in the key names (``median_ms``, ``p95_ms``, ``mev_per_s``, ``peak_rss_mb``).
Timing is never asserted in unit tests; it is measured here.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path

AREAS = ("io", "sim", "mapping", "frontend", "tracking", "fusion", "slam")


@dataclass
class BenchContext:
    """What a benchmark may use."""

    quick: bool
    """True for the quick suite (< 5 min in all), False for the full suite."""
    work_dir: Path
    """Scratch/cache folder for generated data; survives between runs for resuming."""
    seed: int = 0


def collect() -> dict[str, object]:
    """All registered benchmarks as ``area.name -> callable``; areas not yet present are skipped."""
    found: dict[str, object] = {}
    for area in AREAS:
        try:
            mod = importlib.import_module(f"evpose.bench.{area}")
        except ModuleNotFoundError as exc:
            if exc.name == f"evpose.bench.{area}":
                continue
            raise
        for name, fn in getattr(mod, "BENCHMARKS", {}).items():
            found[f"{area}.{name}"] = fn
    return found
