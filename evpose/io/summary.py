"""Summaries of recordings, maps and trajectories for ``evpose info``, computed without loading all events."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evpose.core.trajectory import Trajectory
from evpose.errors import InputError


def _longest_gap(t: np.ndarray, t_before: int | None, best: tuple[int, int]) -> tuple[int, int]:
    """``best`` = (longest gap between consecutive events so far, us; the time of the event before it), updated with the
    timestamps ``t`` of the next batch (``t_before``: the last event before it, None for the first batch)."""
    if not len(t):
        return best
    if t_before is not None and int(t[0]) - t_before > best[0]:
        best = (int(t[0]) - t_before, t_before)
    if len(t) > 1:
        d = np.diff(t)
        i = int(np.argmax(d))
        if int(d[i]) > best[0]:
            best = (int(d[i]), int(t[i]))
    return best


def summarize_recording(path: str | Path, width: int | None = None, height: int | None = None, progress: bool | None = None, **options) -> dict:
    """The keys of :meth:`Recording.summary`, streaming the events (evpose HDF5 reads only its index and polarity)."""
    from evpose.io.open import SourceFormat, apply_size_flags, check_events, detect_format, open_stream

    path = Path(path)
    fmt = detect_format(path)
    if fmt is SourceFormat.EVPOSE_H5:
        from evpose.io.h5 import H5RecordingReader

        with H5RecordingReader(path) as r:
            rec = r.to_recording(0, 0)
            rec.imu, rec.ground_truth = r.imu, r.ground_truth
            if (width is None) != (height is None):
                from evpose.errors import ConfigError

                raise ConfigError("give both width and height of the sensor, or neither")
            apply_size_flags(path, rec, width, height)
            n, t0, t1 = r.n_events, r.t_start_us, r.t_end_us
            pos, offset, last, size = 0, 0, None, rec.sensor_size
            gap = (0, t0)
            for b in r.iter_chunks():
                # The same checks as every reader's (``open_recording``): info must not describe a broken file as fine.
                check_events(b, offset, last, size, path)
                gap = _longest_gap(b.t, last, gap)
                offset, last = offset + len(b), (int(b.t[-1]) if len(b) else last)
                pos += int(np.count_nonzero(b.p > 0))
    else:
        import sys

        from tqdm import tqdm

        stream = open_stream(path, width, height, **options)
        rec = stream.context
        n, pos, t0, t1 = 0, 0, 0, 0
        gap = (0, 0)
        disable = (not sys.stderr.isatty()) if progress is None else (not progress)
        with tqdm(total=stream.progress_total, unit=stream.progress_unit, unit_scale=True, desc=f"scan {path.name}", file=sys.stderr, disable=disable, mininterval=0.5) as bar:
            for b in stream.batches(bar.update):
                if len(b) == 0:
                    continue
                if n == 0:
                    t0 = int(b.t[0])
                gap = _longest_gap(b.t, t1 if n else None, gap)
                t1 = int(b.t[-1])
                n += len(b)
                pos += int(np.count_nonzero(b.p > 0))
    if n == 0:
        raise InputError(path, "contains no events")
    for stream_ in (rec.imu, rec.ground_truth):
        if stream_ is not None:
            stream_.validate(source=str(path))
    out = rec.summary()
    dur = (t1 - t0) / 1e6 if n else 0.0
    out.update(
        source=str(path),
        format=fmt.value,
        events=n,
        t_start_us=t0,
        t_end_us=t1,
        duration_s=dur,
        event_rate_hz=n / dur if dur > 0 else 0.0,
        positive_share=pos / n if n else 0.0,
        # ``evpose track`` restarts after a gap longer than ``max_event_gap_ms``: info names the longest one.
        longest_event_gap_s=gap[0] / 1e6,
        longest_event_gap_after_us=gap[1],
        ground_truth=rec.ground_truth is not None and len(rec.ground_truth) > 0,
        metadata=rec.metadata,
    )
    return out


def summarize_trajectory(traj: Trajectory, source: str | Path) -> dict:
    steps = np.linalg.norm(np.diff(traj.position, axis=0), axis=1) if len(traj) > 1 else np.zeros(0)
    return {
        "source": str(source),
        "format": "tum",
        "poses": len(traj),
        "t_start_us": int(traj.t[0]),
        "t_end_us": int(traj.t[-1]),
        "duration_s": float((traj.t[-1] - traj.t[0]) / 1e6),
        "rate_hz": float(1e6 / np.median(np.diff(traj.t))) if len(traj) > 1 else 0.0,
        "path_length_m": float(steps.sum()),
    }


def summarize_map(path: str | Path) -> dict:
    from evpose.io.map_ply import read_contour_map

    cmap = read_contour_map(path)
    lo, hi = cmap.bounds()
    regions = np.unique(cmap.region_id[cmap.region_id >= 0])
    return {
        "source": str(path),
        "format": "map",
        "points": len(cmap),
        "bounds_min_m": lo.tolist(),
        "bounds_max_m": hi.tolist(),
        "regions": int(regions.size),
        "edge_normals": bool(cmap.has_edge_normals),
        "plane_normals": bool(np.any(cmap.plane_normal != 0)),
        "brightness_signs": bool(np.any(cmap.brightness_sign != 0)),
        "brightness_signs_known_share": float(np.mean(cmap.brightness_sign != 0)),
    }
