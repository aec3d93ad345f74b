"""Far-seek benchmarks on the engine alone (part of ``python -m app.bench --only far_seek``): a fresh opening's far seek
(:func:`far_seek_once`), and the same seek in a *partly prepared* recording, whose disk cache holds only its first
half (a warm-up cut short, a recording watched half-way): with the disk snapshots (``DiskCacheConfig.snapshots``) it
resumes from the one at the half, without them from step 0 (:func:`far_seek_partly_prepared`)."""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import numpy as np


def far_seek_once(rec, cmap, t_us: int, catch_up: bool, disk=None, exact: bool = False) -> dict:
    """A fresh engine as the viewer opens it (first step shown, a few run-ahead steps), then one far seek.
    ``disk``: the engine's disk cache entry maker (default: none); ``exact``: to that step (else the grid step)."""
    from app.tracker_engine import TrackerEngine

    eng = TrackerEngine(rec, cmap, disk=disk)
    eng.seek(rec.t_start_us)
    eng.prefetch(5)
    load0 = os.getloadavg()[0]
    steps = eng.catch_up_steps(t_us, exact)
    w0, c0 = time.perf_counter(), time.thread_time()
    slices = 0
    if catch_up:
        while not eng.catch_up(t_us, 25, exact):
            slices += 1
    frame = eng.seek(t_us) if exact else eng.seek_near(t_us)
    out = {"wall_s": time.perf_counter() - w0, "cpu_s": time.thread_time() - c0, "index": frame.index,
           "steps": steps if disk is not None else frame.index, "slices": slices + 1 if catch_up else 0,
           "kept_frames": len(eng.cache), "loadavg_1min": [load0, os.getloadavg()[0]], "pose": frame.pose}
    if disk is not None:
        # Read, unpickle, rebuild the smoothers from their last re-base and replay their journal since.
        out["disk_restore_s"] = eng._disk_restore_s  # one restore in a fresh engine (0: none)
        out["disk_replayed_entries"] = eng.disk.replayed_entries
        out["disk_snapshot_step"] = frame.index - steps
        out["plain_step_s"] = eng._step_s["plain"]  # the tracker's running estimate, for the steps after the restore
        out["snapshot_cpu_s_during_seek"] = eng.disk_snapshot_cpu_s  # later ones are queued: 0 unless > MAX_QUEUED
        return out
    # A later seek half-way back: from a kept frame (old path) or a snapshot and a few steps (catch-up path).
    t0 = time.perf_counter()
    eng.seek_near(rec.t_start_us + (t_us - rec.t_start_us) // 2 + 7_000)
    out["then_mid_seek_ms"] = (time.perf_counter() - t0) * 1e3
    return out


def _maker(rec_path: Path, map_path: Path, directory: Path, snapshots: bool):
    from app.disk_cache import DiskCache, DiskCacheConfig, cache_key

    conf = DiskCacheConfig(directory=directory, snapshots=snapshots)
    return lambda config, every: DiskCache(conf, *cache_key(rec_path, map_path, config, every))


def _prepare_half(rec, cmap, maker, fraction: float = 0.5) -> dict:
    """The run-ahead of a fresh engine with a disk cache stepped to the chunk end nearest ``fraction`` of the
    recording (1: to its end)."""
    from app.tracker_engine import TrackerEngine

    eng = TrackerEngine(rec, cmap, disk=maker)
    c = eng.disk.chunk_steps
    half = max(c, int(round(eng.n_steps * fraction / c)) * c) if fraction < 1 else eng.n_steps + 1
    eng.seek(rec.t_start_us)
    load0 = os.getloadavg()[0]
    w0, c0 = time.perf_counter(), time.thread_time()
    while eng.frontier < half and eng.prefetch(25):
        pass
    while fraction >= 1 and eng.prefetch(25):  # to the end, and the frames a catch-up skipped
        pass
    eng.flush_disk_snapshots()  # the last ones may still be on the encoder thread
    cpu = time.thread_time() - c0
    # Encoding runs on the encoder thread: its CPU relative to the run-ahead's, and what writing costs the run-ahead.
    return {"wall_s": time.perf_counter() - w0, "cpu_s": cpu, "snapshot_cpu_share": eng.disk_snapshot_cpu_s / cpu,
            "snapshot_write_cpu_share": eng.disk_snapshot_write_cpu_s / cpu,
            "steps": eng.frontier,
            "half_steps": half, "loadavg_1min": [load0, os.getloadavg()[0]], "dir": eng.disk.dir,
            "step_us": eng.step_us, "chunk_steps": c}


def far_seek_partly_prepared(rec_path: Path, map_path: Path, rec, cmap, t_us: int, work_dir: Path,
                             pairs: int = 2) -> dict:
    """Write phase: the first half prepared into an empty cache with and without disk snapshots, alternated
    (``pairs`` each, one process): run-ahead time and the snapshot files' size. Seek phase: a fresh opening of
    that half-prepared entry seeks to ``t_us`` with snapshots on and off (the same chunks; off = computing from step
    0 as before), alternated, each from a pristine copy (a seek's run-ahead writes later snapshots); the two poses
    must be equal bit for bit."""
    root = Path(work_dir) / "partly_prepared"
    shutil.rmtree(root, ignore_errors=True)
    out: dict = {"write": {"snapshots_on": [], "snapshots_off": []}, "seek": {"snapshots_on": [], "snapshots_off": []}}
    pristine = None
    for i in range(pairs):
        for on in (True, False):
            d = root / f"write_{'on' if on else 'off'}_{i}"
            r = _prepare_half(rec, cmap, _maker(rec_path, map_path, d, on))
            entry = r.pop("dir")
            out["write"]["snapshots_on" if on else "snapshots_off"].append(r)
            if on and pristine is None:
                pristine = d
                snaps = sorted(entry.glob("snap_*.pkl"))
                chunks = sorted(entry.glob("chunk_*.pkl"))
                per_s = r["chunk_steps"] * r["step_us"] / 1e6
                out["sizes"] = {
                    "snapshot_files": len(snaps), "chunk_files": len(chunks),
                    "snapshot_mb_each": [round(p.stat().st_size / 2**20, 3) for p in snaps],
                    "snapshot_mb_per_recording_s": sum(p.stat().st_size for p in snaps) / 2**20 / (len(snaps) * per_s),
                    "chunk_mb_per_recording_s": sum(p.stat().st_size for p in chunks) / 2**20 / (len(chunks) * per_s),
                    "journal_mb_each": [round(_header_bytes(p) / 2**20, 3) for p in snaps]}
            elif not on:
                shutil.rmtree(d, ignore_errors=True)
    for name in ("on", "off"):
        w = out["write"][f"snapshots_{name}"]
        out["write"][f"{name}_mean_wall_s"] = float(np.mean([r["wall_s"] for r in w]))
        out["write"][f"{name}_mean_cpu_s"] = float(np.mean([r["cpu_s"] for r in w]))
    out["write"]["cpu_ratio_on_over_off"] = out["write"]["on_mean_cpu_s"] / out["write"]["off_mean_cpu_s"]
    poses = []
    for i in range(pairs):
        for on in (True, False):
            d = root / f"seek_{i}_{int(on)}"
            shutil.copytree(pristine, d)
            r = far_seek_once(rec, cmap, t_us, True, _maker(rec_path, map_path, d, on))
            poses.append(r.pop("pose"))
            out["seek"]["snapshots_on" if on else "snapshots_off"].append(r)
            shutil.rmtree(d, ignore_errors=True)
    out["seek"]["poses_bit_identical"] = all(np.array_equal(p, poses[0]) for p in poses)
    for name in ("on", "off"):
        s = out["seek"][f"snapshots_{name}"]
        out["seek"][f"{name}_mean_wall_s"] = float(np.mean([r["wall_s"] for r in s]))
        out["seek"][f"{name}_mean_cpu_s"] = float(np.mean([r["cpu_s"] for r in s]))
    out["seek"]["cpu_ratio_on_over_off"] = out["seek"]["on_mean_cpu_s"] / out["seek"]["off_mean_cpu_s"]
    # Through the player (run-ahead on, as ``evpose app`` runs it), once each: when the frame is drawn.
    from app.bench import _far_seek_player
    from app.engine_factory import engine_factory
    from app.frame_cache import FrameCacheConfig

    for on in (True, False):
        d = root / f"player_{int(on)}"
        shutil.copytree(pristine, d)
        from app.disk_cache import DiskCacheConfig

        factory = engine_factory(rec, cmap, "tracking", FrameCacheConfig(), DiskCacheConfig(directory=d, snapshots=on),
                                 (Path(rec_path).resolve(), Path(map_path).resolve()))
        r = _far_seek_player(rec, cmap, t_us, factory)
        out["seek"][f"player_snapshots_{'on' if on else 'off'}"] = {
            k: r[k] for k in ("frame_drawn_s", "command_wait_while_computing_ms", "loadavg_1min")}
        shutil.rmtree(d, ignore_errors=True)
    shutil.rmtree(root, ignore_errors=True)
    return out


def exact_seek_prepared(rec_path: Path, map_path: Path, rec, cmap, t_us: int, work_dir: Path, pairs: int = 2) -> dict:
    """A recording prepared to its end (disk snapshots on), then a fresh opening's *exact* seek to the step at
    ``t_us`` (off the kept-frame grid), with the disk snapshots vs without them (which waits for the run-ahead to
    step there), alternated; the poses must be equal bit for bit."""
    root = Path(work_dir) / "exact_prepared"
    shutil.rmtree(root, ignore_errors=True)
    prep = _prepare_half(rec, cmap, _maker(rec_path, map_path, root / "entry", True), fraction=1.0)
    prep.pop("dir")
    out: dict = {"prepare": prep, "snapshots_on": [], "snapshots_off": []}
    poses = []
    for _ in range(pairs):
        for on in (True, False):
            r = far_seek_once(rec, cmap, t_us, True, _maker(rec_path, map_path, root / "entry", on), exact=True)
            poses.append(r.pop("pose"))
            out["snapshots_on" if on else "snapshots_off"].append(r)
    out["poses_bit_identical"] = all(np.array_equal(p, poses[0]) for p in poses)
    for name in ("on", "off"):
        out[f"{name}_mean_wall_s"] = float(np.mean([r["wall_s"] for r in out[f"snapshots_{name}"]]))
    on = out["snapshots_on"]
    out["on_restore_s"] = [r["disk_restore_s"] for r in on]
    out["on_replayed_entries"] = [r["disk_replayed_entries"] for r in on]
    shutil.rmtree(root, ignore_errors=True)
    return out


def _header_bytes(path: Path) -> int:
    """Bytes of a snapshot file's header (its fusion journal segment), the rest being the state."""
    import pickle

    with open(path, "rb") as f:
        pickle.load(f)
        return f.tell()
