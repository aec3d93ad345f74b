"""Summaries every benchmark reports the same way."""

from __future__ import annotations

import resource
import time

import numpy as np


def latency_summary(samples_ms, prefix: str = "") -> dict[str, float]:
    """median / p95 / p99 / mean / max of latency samples in milliseconds."""
    a = np.asarray(list(samples_ms), dtype=np.float64)
    if a.size == 0:
        return {}
    return {
        f"{prefix}median_ms": float(np.median(a)),
        f"{prefix}p95_ms": float(np.percentile(a, 95)),
        f"{prefix}p99_ms": float(np.percentile(a, 99)),
        f"{prefix}mean_ms": float(a.mean()),
        f"{prefix}max_ms": float(a.max()),
        f"{prefix}n": int(a.size),
    }


def repeat_timing(fn, repeats: int = 7, warmup: int = 1) -> list[float]:
    """Wall times of ``fn()`` in milliseconds, after ``warmup`` untimed calls (numba compilation)."""
    for _ in range(warmup):
        fn()
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        out.append((time.perf_counter() - t0) * 1e3)
    return out


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far, MiB (Linux ru_maxrss is KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
