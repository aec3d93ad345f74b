"""Job functions the sweep and the bench suite run: pure functions of JSON-able parameters.

Each returns ``{"metrics": {...}, "timing": {...}}``: ``metrics`` depend only on
the parameters (bit-identical wherever the job runs, which the Dask test
checks); ``timing`` holds wall-clock measurements, which do not.
"""

from __future__ import annotations

import time

import numpy as np

from evpose.eval.recordings import load_recording


def _sensor_size(rec, spec: str) -> tuple[int, int]:
    from evpose.errors import InputError

    size = rec.sensor_size
    if size is None:
        raise InputError(spec, "recording has no sensor size (no calibration, no width/height metadata)")
    return size


def noise_filter_job(config: dict, recording: str) -> dict:
    """Run the consistency noise filter with ``config`` (a NoiseFilterConfig as a dict) over a whole recording.

    Metrics: events in, events kept, kept share. Timing: filter wall time and throughput.
    """
    from evpose.frontend.noise_filter import ConsistencyNoiseFilter, NoiseFilterConfig
    from evpose.tracker.config import config_from_dict

    cfg = config_from_dict(NoiseFilterConfig, config, source="sweep config")
    rec = load_recording(recording)
    width, height = _sensor_size(rec, recording)
    filt = ConsistencyNoiseFilter(cfg, width, height)
    t0 = time.perf_counter()
    keep = filt.filter(rec.events)
    dt = time.perf_counter() - t0
    n = len(rec.events)
    kept = int(np.count_nonzero(keep))
    metrics = {"events": n, "events_kept": kept, "kept_share": kept / n if n else 0.0}
    return {"metrics": metrics, "timing": {"filter_ms": dt * 1e3, "mev_per_s": n / dt / 1e6 if dt > 0 else 0.0}}
