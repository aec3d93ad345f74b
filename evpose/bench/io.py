"""I/O benchmarks: ECD text -> HDF5 conversion rate and peak memory, HDF5 window reads, bag EventArray decoding.

Each figure is compared with a baseline measured in the same run (pandas' C
parser on the same text file; rosbags' per-message deserialisation on the same
bag), because the 2-core machine is shared and absolute timings are noisy.
The conversion runs in a child process so its peak RSS is its own.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from evpose.bench import BenchContext
from evpose.bench.stats import latency_summary

_BLOCK = 1 << 20


def synthetic_ecd_folder(folder: Path, n_events: int, seed: int = 0) -> Path:
    """A DAVIS240C-like ``events.txt`` of ``n_events`` lines (~1 Mev/s), written block by block; reused if present."""
    from evpose.io import ecd_text

    events = folder / "events.txt"
    done = folder / ".complete"
    if done.is_file() and done.read_text() == str(n_events):
        return folder
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    t_last = 0
    tmp = folder / "events.txt.part"
    buf = np.empty(48 * _BLOCK, np.uint8)
    with open(tmp, "wb") as fh:
        for i0 in range(0, n_events, _BLOCK):
            n = min(_BLOCK, n_events - i0)
            t = t_last + np.cumsum(rng.integers(0, 3, n))
            t_last = int(t[-1])
            x = rng.integers(0, 240, n).astype(np.uint16)
            y = rng.integers(0, 180, n).astype(np.uint16)
            p = np.where(rng.integers(0, 2, n) > 0, 1, -1).astype(np.int8)
            used = ecd_text.format_event_lines(t.astype(np.int64), x, y, p, buf)
            fh.write(memoryview(buf)[:used])
    tmp.replace(events)
    done.write_text(str(n_events))
    return folder


def _child_convert(src: str, dst: str, threaded: str = "1") -> None:
    """Run in a subprocess: convert and print rate and this process's peak RSS as JSON."""
    from evpose.bench.stats import peak_rss_mb
    from evpose.io.convert import convert_to_h5

    cpu0 = time.process_time()
    res = convert_to_h5(src, dst, 240, 180, progress=False, threaded=threaded == "1")
    cpu = time.process_time() - cpu0  # all threads; less sensitive to other processes than wall time
    print(json.dumps({"events": res.events, "seconds": res.seconds, "cpu_seconds": cpu, "peak_rss_mb": peak_rss_mb()}))


def _pandas_rate(events_txt: Path, max_lines: int) -> float:
    import pandas as pd

    t0 = time.perf_counter()
    n = 0
    reader = pd.read_csv(events_txt, sep=" ", header=None, engine="c", chunksize=2_000_000, nrows=max_lines, dtype={0: np.float64, 1: np.int32, 2: np.int32, 3: np.int8})
    for chunk in reader:
        n += len(chunk)
    return n / (time.perf_counter() - t0) / 1e6


def _our_parse_rate(events_txt: Path, max_lines: int) -> float:
    from evpose.io.ecd import iter_ecd_events

    t0 = time.perf_counter()
    n = 0
    for b in iter_ecd_events(events_txt, 240, 180):
        n += len(b)
        if n >= max_lines:
            break
    return n / (time.perf_counter() - t0) / 1e6


def bench_ecd_to_h5(ctx: BenchContext) -> dict:
    n = 5_000_000 if ctx.quick else 100_000_000
    folder = synthetic_ecd_folder(ctx.work_dir / f"ecd_{n}", n, ctx.seed)
    dst = ctx.work_dir / f"ecd_{n}.h5"
    # Warm the numba cache in a throwaway child so the timed child loads compiled code.
    tiny = synthetic_ecd_folder(ctx.work_dir / "ecd_warmup", 1000, ctx.seed)
    code = "import sys; from evpose.bench.io import _child_convert; _child_convert(*sys.argv[1:])"
    subprocess.run([sys.executable, "-c", code, str(tiny), str(ctx.work_dir / "warm.h5")], check=True, capture_output=True)

    def child(threaded: bool) -> dict:
        proc = subprocess.run([sys.executable, "-c", code, str(folder), str(dst), "1" if threaded else "0"], check=True, capture_output=True, text=True)
        return json.loads(proc.stdout.strip().splitlines()[-1])

    out = {"events": n, "text_mb": (folder / "events.txt").stat().st_size / 1e6}
    # Interleave the pandas baseline with our runs so both see the same machine load.
    runs = 1 if not ctx.quick else 2
    conv, cpu, seq, base, ours, rss = [], [], [], [], [], []
    _our_parse_rate(tiny / "events.txt", 1000)  # load the numba cache in this process
    for _ in range(runs):
        r = child(True)
        conv.append(r["events"] / r["seconds"] / 1e6)
        cpu.append(r["events"] / r["cpu_seconds"] / 1e6)
        rss.append(r["peak_rss_mb"])
        base.append(_pandas_rate(folder / "events.txt", min(n, 20_000_000)))
        ours.append(_our_parse_rate(folder / "events.txt", min(n, 20_000_000)))
        if ctx.quick:
            r = child(False)
            seq.append(r["events"] / r["seconds"] / 1e6)
    out.update(
        h5_mb=dst.stat().st_size / 1e6,
        convert_mev_per_s=float(np.median(conv)),
        convert_mev_per_cpu_s=float(np.median(cpu)),
        load_avg_1min=float(os.getloadavg()[0]),
        peak_rss_mb=float(max(rss)),
        parse_only_mev_per_s=float(np.median(ours)),
        baseline_pandas_parse_only_mev_per_s=float(np.median(base)),
    )
    if seq:
        out["convert_unthreaded_mev_per_s"] = float(np.median(seq))
    return out


def bench_h5_window_read(ctx: BenchContext) -> dict:
    from evpose.io.h5 import H5RecordingReader

    n = 5_000_000
    src = synthetic_ecd_folder(ctx.work_dir / f"ecd_{n}", n, ctx.seed)
    path = ctx.work_dir / "window.h5"
    if not path.is_file():
        from evpose.io.convert import convert_to_h5

        convert_to_h5(src, path, 240, 180, progress=False)
    rng = np.random.default_rng(ctx.seed)
    out: dict = {}
    with H5RecordingReader(path) as r:
        t0, t1 = r.t_start_us, r.t_end_us
        for length_ms in (10, 1000):
            lat, counts = [], 0
            for s in rng.integers(t0, t1 - length_ms * 1000, 30 if ctx.quick else 200):
                a = time.perf_counter()
                ev = r.read_events(int(s), int(s) + length_ms * 1000)
                lat.append((time.perf_counter() - a) * 1e3)
                counts += len(ev)
            out.update(latency_summary(lat, prefix=f"window_{length_ms}ms_"))
            out[f"window_{length_ms}ms_mev_per_s"] = counts / (sum(lat) / 1e3) / 1e6
        # Playback order (what the tracker does): consecutive 10 ms windows, served from the chunk cache.
        lat, t = [], t0
        for _ in range(100 if ctx.quick else 1000):
            a = time.perf_counter()
            r.read_events(t, t + 10_000)
            lat.append((time.perf_counter() - a) * 1e3)
            t += 10_000
        out.update(latency_summary(lat, prefix="sequential_10ms_"))
        a = time.perf_counter()
        full = r.read_events()
        out["full_read_mev_per_s"] = len(full) / (time.perf_counter() - a) / 1e6
    out["events"] = int(len(full))
    return out


def bench_bag_decode(ctx: BenchContext) -> dict:
    from evpose.core.events import EventArray
    from evpose.core.recording import Recording
    from evpose.io.open import open_stream
    from evpose.io.rosbag import EVENT_ARRAY, make_typestore, write_rosbag

    n = 2_000_000 if ctx.quick else 20_000_000
    out: dict = {"events": n}
    for ros2 in (False, True):
        tag = "ros2" if ros2 else "ros1"
        path = ctx.work_dir / (f"events_{n}_ros2" if ros2 else f"events_{n}.bag")
        if not path.exists():
            rng = np.random.default_rng(ctx.seed)
            t = np.cumsum(rng.integers(0, 3, n))
            ev = EventArray.from_arrays(t, rng.integers(0, 346, n), rng.integers(0, 260, n), rng.integers(0, 2, n))
            write_rosbag(path, Recording(ev, metadata={"width": 346, "height": 260}), ros2=ros2, events_per_message=20_000)
        stream = open_stream(path)
        rates, cpu_rates = [], []
        for _ in range(1 + (3 if ctx.quick else 2)):  # the first pass warms numba and the page cache
            a, c = time.perf_counter(), time.process_time()
            got = sum(len(b) for b in stream.batches(None))
            rates.append(got / (time.perf_counter() - a) / 1e6)
            cpu_rates.append(got / (time.process_time() - c) / 1e6)
        out[f"{tag}_decode_mev_per_s"] = float(np.median(rates[1:]))
        out[f"{tag}_decode_best_mev_per_s"] = float(max(rates[1:]))
        out[f"{tag}_decode_mev_per_cpu_s"] = float(np.median(cpu_rates[1:]))
        # Baseline: rosbags' own deserialiser (one Python object per event) on the first messages.
        from rosbags.highlevel import AnyReader

        store = make_typestore()
        with AnyReader([path], default_typestore=store) as reader:
            conns = [c for c in reader.connections if c.msgtype == EVENT_ARRAY]
            a, m = time.perf_counter(), 0
            for k, (c, _, raw) in enumerate(reader.messages(connections=conns)):
                msg = reader.deserialize(raw, c.msgtype)
                m += len(msg.events)
                if k == 9:
                    break
            out[f"{tag}_baseline_rosbags_deserialize_mev_per_s"] = m / (time.perf_counter() - a) / 1e6
    out["load_avg_1min"] = float(os.getloadavg()[0])
    return out


BENCHMARKS = {
    "ecd_to_h5": bench_ecd_to_h5,
    "h5_window_read": bench_h5_window_read,
    "bag_decode": bench_bag_decode,
}
