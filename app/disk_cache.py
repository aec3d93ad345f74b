"""A persistent cache of what the run-ahead computed: step summaries and kept display frames, on disk.

A second opening of the same recording with the same map and configuration reads
them back instead of recomputing, so playback and (grid-snapped) seeks anywhere
answer at once. The key is exact: a hash of the recording file's bytes, the map
file's bytes, the tracker configuration (its full ``repr``), the frame grid, the
source code of the tracker and of what it may import (:data:`KEYED_SOURCES`) and
the versions of the numeric libraries. Anything
that could change a result changes the key, so what is read back is what a
headless run computes now.

Layout: ``<directory>/<key>/meta.json`` (what the key was made of, for people)
and ``chunk_<n>.pkl``, one per ``chunk_steps`` steps, each written atomically
once the run-ahead has passed it: ``{"summaries": [...], "frames": {index: packed
fields}}``. Only chunks from the first one on without a gap are read. Entries
are dropped least recently used first to stay within ``budget_mb`` (every file
of an entry counts). Beside them ``snap_<n>.pkl``: the engine snapshot at step
``(n + 1) * chunk_steps`` (``app/disk_snapshots.py``), so a seek past the
in-memory frontier restores the farthest one at or before it instead of
computing from step 0; snapshot ``n`` needs the files from the one holding the
fusion smoother's last re-base to ``n`` (each holds the fusion journal since the
previous one or since a re-base in it), and is only written after ``0..n-1``.

The files are Python pickles of our own making in the user's cache folder; a
file that cannot be read is treated as missing (and removed), never an error.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import shutil
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from app.frame import StepSummary
from evpose.io.atomic import atomic_path

ROOT = Path(__file__).resolve().parent.parent
"""The source tree whose code is hashed into the key."""
KEYED_SOURCES = ("evpose/__init__.py", "evpose/blas_kernels.py", "evpose/errors.py", "evpose/core", "evpose/io", "evpose/frontend",
                 "evpose/fusion", "evpose/tracker", "app/browser.py", "app/disk_cache.py", "app/disk_snapshots.py", "app/engine.py",
                 "app/frame.py", "app/frame_cache.py", "app/tracker_engine.py")
"""Everything that can change a cached step: the tracker and what it may import (DEVELOPERS.md layers: core,
io, frontend, fusion), the loaders, and the viewer's frame code. Edits elsewhere (SLAM, mapping, the server)
keep the entries; ``tests/app/test_disk_cache.py`` checks that these files import nothing outside the list."""


@dataclass
class DiskCacheConfig:
    """Where and how much of the run-ahead's work is kept between openings."""

    enabled: bool = True
    """Keep summaries and display frames on disk, keyed by recording, map, configuration and source code."""
    directory: Path | None = None
    """Cache folder; None: ``$XDG_CACHE_HOME/evpose/viewer`` (``~/.cache/evpose/viewer``). Never inside a data folder."""
    budget_mb: float = field(default=2048.0, metadata={"min": 64.0, "max": 65536.0, "step": 64.0, "unit": "MB"})
    """Most disk space all entries together may use; the least recently used go first, MB."""
    chunk_steps: int = field(default=100, metadata={"min": 10, "max": 10000, "step": 10, "unit": "steps"})
    """Steps per file (written once the run-ahead has passed all of them), steps. An exact seek in a new opening
    replays at most this many steps from the snapshot on disk before it: with 200 (1 s at 200 Hz) an exact seek at
    3.8 s into the prepared 4 s demo took 1.05-1.13 s on the session-10 machine (6.1-7.3 ms per plain step, load
    0.9; ``python -m app.bench --only far_seek``, ``exact_prepared``), so 100."""
    snapshots: bool = True
    """Also store an engine snapshot at each chunk's end, so a seek past what the run-ahead has computed in this
    opening resumes from the farthest one on disk instead of step 0 (10 s landing, disk holding its first 5 s: seek
    to 9.5 s from the 5 s snapshot instead of step 0; see README / ``python -m app.bench --only far_seek``)."""

    def folder(self) -> Path:
        if self.directory is not None:
            return Path(self.directory).expanduser()
        base = os.environ.get("XDG_CACHE_HOME") or "~/.cache"
        return Path(base).expanduser() / "evpose" / "viewer"


_FILE_HASHES: dict[tuple, str] = {}
"""(path, size, mtime_ns) -> content hash, so reopening a recording does not read it twice."""


def file_hash(path: Path) -> str:
    """blake2b of a file's bytes, or of a folder recording's files (an ECD folder, a ROS2 bag: their relative names
    and bytes, in sorted order), memoised on path, sizes and modification times."""
    p = Path(path).resolve()
    files = sorted(f for f in p.rglob("*") if f.is_file()) if p.is_dir() else [p]
    stats = [f.stat() for f in files]
    key = (str(p), tuple((str(f), st.st_size, st.st_mtime_ns) for f, st in zip(files, stats)))
    if key not in _FILE_HASHES:
        h = hashlib.blake2b(digest_size=20)
        for f in files:
            if p.is_dir():
                h.update(str(f.relative_to(p)).encode() + b"\0")
            with open(f, "rb") as fh:
                while chunk := fh.read(1 << 22):
                    h.update(chunk)
        _FILE_HASHES[key] = h.hexdigest()
    return _FILE_HASHES[key]


def keyed_files(root: Path = ROOT) -> list[Path]:
    """The ``.py`` files of :data:`KEYED_SOURCES`, sorted."""
    out = []
    for rel in KEYED_SOURCES:
        p = root / rel
        out.extend(sorted(p.rglob("*.py")) if p.is_dir() else [p])
    return sorted(out)


def source_hash(root: Path = ROOT) -> str:
    """Hash of the :data:`KEYED_SOURCES` files (path and bytes) and the numeric libraries' versions."""
    import numba
    import numpy

    h = hashlib.blake2b(digest_size=20)
    h.update(f"{sys.version}|numpy {numpy.__version__}|numba {numba.__version__}".encode())
    try:
        import gtsam

        h.update(f"|gtsam {getattr(gtsam, '__version__', '?')}".encode())
    except ImportError:
        h.update(b"|no gtsam")
    for f in keyed_files(root):
        h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes() + b"\0")
    return h.hexdigest()


def config_text(config) -> str:
    """The configuration's full ``repr`` (arrays written out whole, never abbreviated with '...')."""
    import numpy

    with numpy.printoptions(threshold=sys.maxsize):
        return repr(config)


def cache_key(recording_path: Path, map_path: Path, config, every_steps: int, sources: str | None = None) -> tuple[str, dict]:
    """The entry's name and what it was made of: any difference in any part gives another name."""
    parts = {
        "recording": str(Path(recording_path).resolve()), "recording_hash": file_hash(recording_path),
        "map": str(Path(map_path).resolve()), "map_hash": file_hash(map_path),
        "config": config_text(config), "every_steps": int(every_steps),
        "sources": sources if sources is not None else source_hash(),
    }
    # Paths are for people reading meta.json; the key is made of contents only (a moved file is the same entry).
    keyed = {k: v for k, v in parts.items() if k not in ("recording", "map")}
    return hashlib.blake2b(json.dumps(keyed, sort_keys=True).encode(), digest_size=16).hexdigest(), parts


class DiskCache:
    """One entry of the cache: read at engine start, written chunk by chunk as the run-ahead passes."""

    def __init__(self, config: DiskCacheConfig, key: str, parts: dict):
        self.config = config
        self.dir = config.folder() / key
        self.key = key
        self.parts = parts
        self.chunk_steps = max(int(config.chunk_steps), 1)
        self.written: set[int] = set()
        """Chunks present on disk (read or written by this process)."""
        self.snapshots_written: set[int] = set()
        """Disk snapshots present on disk (found or written by this process)."""
        self.error = ""
        """Why writing stopped (disk full, no permission...); empty while it works."""
        self.replayed_entries = 0
        """Fusion journal entries the last disk snapshot restore replayed (its cost, which the re-bases bound)."""

    def _chunk_path(self, n: int) -> Path:
        return self.dir / f"chunk_{n:05d}.pkl"

    def _snapshot_path(self, n: int) -> Path:
        return self.dir / f"snap_{n:05d}.pkl"

    def snapshot_step(self, n: int) -> int:
        """Step count of disk snapshot ``n``: after chunk ``n``."""
        return (n + 1) * self.chunk_steps

    def snapshot_chunks(self) -> list[int]:
        """Disk snapshots present from the first on without a gap (a later one needs every earlier file)."""
        out = []
        while self.config.snapshots and self._snapshot_path(len(out)).is_file():
            out.append(len(out))
        self.snapshots_written.update(out)
        return out

    def want_snapshot(self, n: int) -> bool:
        return self.config.snapshots and not self.error and n not in self.snapshots_written

    def write_snapshot(self, n: int, header: bytes, body: bytes) -> None:
        """Store disk snapshot ``n`` (atomically: a reader sees the whole file or none); on failure stop writing."""
        if not self.want_snapshot(n):
            return
        try:
            self.dir.mkdir(parents=True, exist_ok=True)
            with atomic_path(self._snapshot_path(n)) as tmp:
                with open(tmp, "wb") as f:
                    f.write(header)
                    f.write(body)
            self.snapshots_written.add(n)
            self.trim()
        except Exception as exc:  # the viewer works without its disk cache
            self.error = f"disk cache off: {exc}"

    def load_snapshot(self, n: int, step0_snapshot):
        """The session snapshot ``(state, cursor)`` of disk snapshot ``n`` (fusion smoothers rebuilt from their last
        re-base, or from step 0's, ``step0_snapshot``), or None if a file it needs cannot be read (see
        :meth:`snapshot_loader`)."""
        loader = self.snapshot_loader(n, step0_snapshot)
        while True:
            try:
                next(loader)
            except StopIteration as stop:
                return stop.value

    def snapshot_loader(self, n: int, step0_snapshot):
        """:meth:`load_snapshot` in slices: a generator that yields after each earlier file's journal segment is
        replayed and returns the snapshot. Only the files from the one holding each smoother's last re-base are
        replayed (the smoother re-bases every ``FactorGraphFusion.rebase_every_states`` updates, so usually the
        snapshot's own file alone), else every file from the first. A file that cannot be read is removed with the
        later ones (the run-ahead writes them again) with a warning, and it returns None: the caller falls back to
        an earlier snapshot."""
        from app.disk_snapshots import finish_rebuild, read_header, read_state, replay_header, replay_start, start_rebuild

        m = n
        try:
            header = read_header(self._snapshot_path(n))
            stored = read_state(self._snapshot_path(n))
            if header["step"] != self.snapshot_step(n):
                raise ValueError("step does not match the file name")
            smoothers = start_rebuild(stored, step0_snapshot)
            # Headers from the last, back to the one holding every smoother's last re-base (usually the last itself).
            headers = {n: header}
            while m > 0 and len(replay_start([headers[j] for j in range(m, n + 1)])) < len(smoothers):
                m -= 1
                headers[m] = read_header(self._snapshot_path(m))
            first = m
            start = {key: first + j for key, j in replay_start([headers[j] for j in range(first, n + 1)]).items()}
            self.replayed_entries = 0
            for m in range(first, n + 1):
                self.replayed_entries += replay_header({k: sm for k, sm in smoothers.items() if start.get(k, 0) <= m},
                                                       headers[m])
                if m < n:
                    yield
            return finish_rebuild(stored, smoothers)
        except Exception as exc:  # truncated, foreign or stale: never trusted, never fatal
            warnings.warn(f"disk snapshot {self._snapshot_path(m)} ignored ({exc!r}); "
                          "an earlier snapshot (or step 0) is used instead", RuntimeWarning, stacklevel=2)
            self.drop_snapshots_from(m)
            return None

    def drop_snapshots_from(self, m: int) -> None:
        """Remove disk snapshots ``m`` and later (they cannot be restored without ``m``)."""
        for path in self.dir.glob("snap_*.pkl"):
            try:
                k = int(path.stem.split("_")[1])
            except (IndexError, ValueError):
                continue
            if k >= m:
                path.unlink(missing_ok=True)
                self.snapshots_written.discard(k)

    def load(self) -> tuple[list[StepSummary], dict[int, tuple[int, dict]]]:
        """Summaries of the steps stored without a gap from step 0, and their kept frames (packed, with sizes)."""
        summaries: list[StepSummary] = []
        frames: dict[int, tuple[int, dict]] = {}
        n = 0
        while (path := self._chunk_path(n)).is_file():
            try:
                with open(path, "rb") as f:
                    chunk = pickle.load(f)
                part, packed = chunk["summaries"], chunk["frames"]
                if [s.index for s in part] != list(range(n * self.chunk_steps, n * self.chunk_steps + len(part))):
                    raise ValueError("step indices out of order")
            except Exception:  # a truncated or foreign file: recompute rather than trust it
                path.unlink(missing_ok=True)
                break
            summaries.extend(part)
            frames.update(packed)
            self.written.add(n)
            if len(part) < self.chunk_steps:
                break  # the last, short chunk of the recording
            n += 1
        if summaries:
            self._touch()
        return summaries, frames

    def want(self, n: int) -> bool:
        return not self.error and n not in self.written

    def write_chunk(self, n: int, summaries: list[StepSummary], frames: dict[int, tuple[int, dict]]) -> None:
        """Store chunk ``n`` (atomically); on failure stop writing and remember why."""
        if not self.want(n):
            return
        try:
            self.dir.mkdir(parents=True, exist_ok=True)
            meta = self.dir / "meta.json"
            if not meta.exists():
                with atomic_path(meta) as tmp:
                    tmp.write_text(json.dumps({**self.parts, "chunk_steps": self.chunk_steps, "created": time.time()}, indent=1))
            with atomic_path(self._chunk_path(n)) as tmp:
                with open(tmp, "wb") as f:
                    pickle.dump({"summaries": summaries, "frames": frames}, f, protocol=pickle.HIGHEST_PROTOCOL)
            self.written.add(n)
            self._touch()
            self.trim()
        except Exception as exc:  # the viewer works without its disk cache
            self.error = f"disk cache off: {exc}"

    def _touch(self) -> None:
        try:
            os.utime(self.dir / "meta.json")
        except OSError:
            pass

    def trim(self) -> None:
        """Drop whole entries, least recently used first, until all fit in the budget (never this one)."""
        root = self.config.folder()
        entries = []
        for d in root.iterdir() if root.is_dir() else ():
            if d.is_dir():
                size = sum(f.stat().st_size for f in d.iterdir() if f.is_file())
                meta = d / "meta.json"
                entries.append((meta.stat().st_mtime if meta.exists() else 0.0, size, d))
        total = sum(e[1] for e in entries)
        budget = self.config.budget_mb * 2**20
        for _, size, d in sorted(entries, key=lambda e: e[0]):
            if total <= budget:
                break
            if d == self.dir:
                continue
            shutil.rmtree(d, ignore_errors=True)
            total -= size
