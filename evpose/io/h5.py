"""The canonical evpose recording file: chunked, compressed HDF5 with a millisecond time index.

The schema is documented in ``docs/recording_h5.md``. In short::

    /                      attrs: evpose_format="recording", evpose_format_version=1,
                                  metadata=<JSON>, calibration=<JSON or absent>
    /events/t x y p        int64 us / uint16 / uint16 / int8 (+1/-1), chunked, compressed
    /events/ms_to_idx      int64; ms_to_idx[k] = first event with t >= t_origin_us + 1000 k
                           (last entry = event count); attr t_origin_us
    /imu/t acc gyro        int64 us (IMU clock) / float64 (N,3) m/s^2 / float64 (N,3) rad/s
    /ground_truth/t position quat_xyzw   int64 us / float64 (N,3) m / float64 (N,4)

Events are written in whole chunks through :class:`H5RecordingWriter`, so a
100-million-event conversion streams with bounded memory; any time window is
read through the index without touching the rest of the file.
"""

from __future__ import annotations

import contextlib
import enum
import json
import os
from dataclasses import dataclass
from pathlib import Path

import h5py
import hdf5plugin  # registers the Blosc filter for reading and writing
import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.core.events import MAX_SPAN_US, EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory, quaternion_problem
from evpose.errors import InputError
from evpose.io.atomic import atomic_path
from evpose.io.hdf5_damage import hdf5_damage, unwritten_problem
from evpose.io.paths import not_a_file

FORMAT_NAME = "recording"
FORMAT_VERSION = 1
_MAX_INDEX_MS = MAX_SPAN_US // 1000  # ~37 hours of millisecond index entries (1 GiB)
_EVENT_COLUMNS = (("t", np.int64), ("x", np.uint16), ("y", np.uint16), ("p", np.int8))


class H5FormatError(InputError):
    """An HDF5 file that is not a readable evpose recording."""


class Compression(str, enum.Enum):
    """Filter applied to the event columns.

    Measured on 5 M synthetic DAVIS240 events (2-core machine, noisy): Blosc LZ4
    with bit-shuffle writes ~90 Mev/s and reads ~130 Mev/s at 14.7 MB; h5py's
    LZF (+shuffle) writes ~20 Mev/s, reads ~31 Mev/s at 16.6 MB; gzip level 1
    writes ~7-11 Mev/s at 13.7 MB. LZF alone would cap the text conversion
    below the 15 Mev/s target, hence Blosc (via ``hdf5plugin``, which DSEC
    files need anyway).
    """

    BLOSC_LZ4 = "blosc-lz4"
    """Blosc LZ4 + bit-shuffle (hdf5plugin); the default."""
    LZF = "lzf"
    """h5py's LZF + byte-shuffle."""
    GZIP1 = "gzip1"
    """zlib level 1 + byte-shuffle: readable by any HDF5 tool without plugins."""
    NONE = "none"
    """No compression (largest files)."""


@dataclass(frozen=True)
class H5WriteConfig:
    """How event columns are laid out on disk."""

    compression: Compression = Compression.BLOSC_LZ4
    """Compression filter of the event columns."""
    chunk_events: int = 1 << 18
    """Events per HDF5 chunk (262144 -> 2 MiB of timestamps), count."""


def _filter_kwargs(cfg: H5WriteConfig) -> dict:
    if cfg.compression is Compression.BLOSC_LZ4:
        return dict(hdf5plugin.Blosc(cname="lz4", clevel=5, shuffle=hdf5plugin.Blosc.BITSHUFFLE))
    if cfg.compression is Compression.LZF:
        return {"compression": "lzf", "shuffle": True}
    if cfg.compression is Compression.GZIP1:
        return {"compression": "gzip", "compression_opts": 1, "shuffle": True}
    return {}


class H5RecordingWriter:
    """Stream a recording into a new HDF5 file; the file appears only when the writer closes cleanly.

    Use as a context manager; call :meth:`append_events` with time-sorted
    batches (sortedness across batches is checked), and set the small streams
    with the ``set_*`` methods at any point before closing.
    """

    def __init__(self, path: str | Path, inputs: tuple = (), config: H5WriteConfig = H5WriteConfig()):
        self.path = Path(path)
        self._inputs = tuple(inputs)
        self._cfg = config
        self._stack: contextlib.ExitStack | None = None
        self._file: h5py.File | None = None
        self._columns: dict[str, h5py.Dataset] = {}
        self._buffer: list[EventArray] = []
        self._buffered = 0
        self._written = 0
        self._last_t: int | None = None
        self._origin: int | None = None
        self._next_k = 0
        self._index_parts: list[np.ndarray] = []
        self._metadata: dict = {}
        self._calibration: CameraCalibration | None = None
        self._imu: ImuSamples | None = None
        self._gt: Trajectory | None = None
        self._source: str | None = None

    # ------------------------------------------------------------ lifecycle
    def __enter__(self) -> "H5RecordingWriter":
        self._stack = contextlib.ExitStack()
        tmp = self._stack.enter_context(atomic_path(self.path, inputs=self._inputs))
        self._file = h5py.File(tmp, "w")
        grp = self._file.create_group("events")
        chunk = int(self._cfg.chunk_events)
        # Held open until the end: closing a dataset writes its cached chunks, and a write failing there (a full disk)
        # is only an "Exception ignored" message, after which HDF5 cannot close the file (see _discard_writes).
        self._columns = {name: grp.create_dataset(name, shape=(0,), maxshape=(None,), dtype=dtype, chunks=(chunk,), **_filter_kwargs(self._cfg))
                         for name, dtype in _EVENT_COLUMNS}
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            try:
                self._finish()
                self._file.flush()  # a full disk fails here, not in close(), where HDF5 cannot recover from it
            except BaseException as err:  # finishing failed: drop the temporary file like any other error
                exc_type, exc, tb = type(err), err, err.__traceback__
        if self._file is not None:
            if exc is not None:
                self._discard_writes()  # before the columns close, which writes their cached chunks
            self._columns = {}
            if exc is None:
                self._file.close()
            else:
                with contextlib.suppress(OSError, RuntimeError):  # after a failed flush: "slist already enabled?"
                    self._file.close()
            self._file = None
        self._stack.__exit__(exc_type, exc, tb)  # deletes the temporary file; a failed write becomes one line
        if exc is not None:
            raise exc

    def _discard_writes(self) -> None:
        """Point HDF5's file descriptor at /dev/null before closing a file that is being dropped. HDF5 writes its
        cached chunks and metadata when closing; on a full disk that failed, left the file open, and every later
        attempt (h5py's, as its objects were freed, and at exit) failed again: pages of "Exception ignored" and a
        segmentation fault. Written to /dev/null, those writes succeed and the close completes."""
        with contextlib.suppress(Exception):
            fd = self._file.id.get_vfd_handle()
            null = os.open(os.devnull, os.O_RDWR)
            os.dup2(null, fd)
            os.close(null)

    # ------------------------------------------------------------ content
    def set_metadata(self, metadata: dict) -> None:
        try:
            json.dumps(metadata)
        except (TypeError, ValueError) as exc:
            raise InputError(self.path, f"metadata is not JSON-serialisable ({exc})") from None
        self._metadata = dict(metadata)

    def set_calibration(self, calibration: CameraCalibration | None) -> None:
        self._calibration = calibration

    def set_imu(self, imu: ImuSamples | None) -> None:
        self._imu = imu

    def set_ground_truth(self, gt: Trajectory | None) -> None:
        self._gt = gt

    @property
    def events_written(self) -> int:
        """Events accepted so far (written or buffered)."""
        return self._written + self._buffered

    def append_events(self, events: EventArray, source: str | None = None) -> None:
        """Append a time-sorted batch; raises InputError if it starts before the previous batch ended."""
        if len(events) == 0:
            return
        if self._last_t is not None and int(events.t[0]) < self._last_t:
            raise InputError(source, f"timestamp {int(events.t[0])} us is earlier than the previous {self._last_t} us (timestamps must be sorted)", f"event {self.events_written}")
        self._last_t = int(events.t[-1])
        self._source = source
        self._buffer.append(events)
        self._buffered += len(events)
        chunk = int(self._cfg.chunk_events)
        if self._buffered >= chunk:
            merged = self._buffer[0] if len(self._buffer) == 1 else EventArray.concatenate(self._buffer)
            # Write whole chunks only, so no compressed chunk is ever read back and rewritten.
            n_full = (self._buffered // chunk) * chunk
            self._write_block(merged[:n_full])
            rest = merged[n_full:]
            self._buffer = [rest] if len(rest) else []
            self._buffered = len(rest)

    def _write_block(self, ev: EventArray) -> None:
        n0, n1 = self._written, self._written + len(ev)
        for name, _ in _EVENT_COLUMNS:
            ds = self._columns[name]
            ds.resize((n1,))
            ds[n0:n1] = getattr(ev, name)
        if self._origin is None:
            self._origin = int(ev.t[0])
        kmax = (int(ev.t[-1]) - self._origin) // 1000
        if kmax > _MAX_INDEX_MS:
            # One bogus far-future timestamp would otherwise allocate an index of billions of entries.
            raise InputError(self._source, f"events span {kmax / 3.6e6:.1f} hours (from {self._origin} to {int(ev.t[-1])} us); timestamps look wrong", f"event {n0 + int(np.argmax(ev.t - self._origin > _MAX_INDEX_MS * 1000))}")
        if kmax >= self._next_k:
            bounds = self._origin + 1000 * np.arange(self._next_k, kmax + 1, dtype=np.int64)
            # All earlier events lie in bins < next_k, so each new bin starts inside this block.
            self._index_parts.append(n0 + np.searchsorted(ev.t, bounds, side="left").astype(np.int64))
            self._next_k = kmax + 1
        self._written = n1

    def _finish(self) -> None:
        if self._buffered:
            self._write_block(EventArray.concatenate(self._buffer))
            self._buffer, self._buffered = [], 0
        f = self._file
        index = np.concatenate(self._index_parts + [np.array([self._written], np.int64)])
        ds = f["events"].create_dataset("ms_to_idx", data=index, dtype=np.int64)
        ds.attrs["t_origin_us"] = np.int64(self._origin if self._origin is not None else 0)
        f["events"].attrs["count"] = np.int64(self._written)
        if self._imu is not None:
            g = f.create_group("imu")
            g.create_dataset("t", data=self._imu.t)
            g.create_dataset("acc", data=self._imu.acc)
            g.create_dataset("gyro", data=self._imu.gyro)
        if self._gt is not None:
            g = f.create_group("ground_truth")
            g.create_dataset("t", data=self._gt.t)
            g.create_dataset("position", data=self._gt.position)
            g.create_dataset("quat_xyzw", data=self._gt.quat_xyzw)
        f.attrs["evpose_format"] = FORMAT_NAME
        f.attrs["evpose_format_version"] = FORMAT_VERSION
        f.attrs["metadata"] = json.dumps(self._metadata, sort_keys=True)
        if self._calibration is not None:
            f.attrs["calibration"] = json.dumps(self._calibration.to_dict(), sort_keys=True)


def write_recording_h5(path: str | Path, recording: Recording, config: H5WriteConfig = H5WriteConfig()) -> None:
    """Write ``recording`` to ``path`` atomically (never onto ``recording.source``)."""
    inputs = (recording.source,) if recording.source is not None else ()
    with H5RecordingWriter(path, inputs=inputs, config=config) as w:
        w.set_metadata(recording.metadata)
        w.set_calibration(recording.calibration)
        w.set_imu(recording.imu)
        w.set_ground_truth(recording.ground_truth)
        w.append_events(recording.events, source=str(recording.source) if recording.source else None)


def is_recording_h5(path: str | Path) -> bool:
    """True if ``path`` is an HDF5 file written by :class:`H5RecordingWriter`."""
    try:
        with h5py.File(path, "r") as f:
            return f.attrs.get("evpose_format") == FORMAT_NAME
    except (OSError, ValueError, KeyError, RuntimeError):  # the last two: a damaged file (see hdf5_damage), named by its reader
        return False


class H5RecordingReader:
    """Lazy, windowed access to an evpose recording file (context manager).

    The small streams (IMU, ground truth, calibration, metadata) are loaded on
    open; events are read on demand through the millisecond index.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not self.path.is_file():
            raise H5FormatError(self.path, not_a_file(self.path))
        try:
            # A chunk cache larger than one chunk of every column keeps small consecutive windows from decompressing the same chunk again.
            self._file = h5py.File(self.path, "r", rdcc_nbytes=32 << 20)
        except OSError:
            raise H5FormatError(self.path, "not an HDF5 file") from None
        try:
            self._load()
        except BaseException as exc:
            self._file.close()
            damage = hdf5_damage(exc)
            if damage is not None:
                raise H5FormatError(self.path, f"the file's HDF5 structure is damaged ({damage})") from None
            raise

    def _need(self, name: str):
        if name not in self._file:
            raise H5FormatError(self.path, f"missing dataset {name!r}")
        return self._file[name]

    def _json_attr(self, name: str):
        raw = self._file.attrs.get(name)
        if raw is None:
            return None
        try:
            return json.loads(raw)
        except (TypeError, ValueError):
            raise H5FormatError(self.path, f"attribute {name!r} is not valid JSON") from None

    def _typed(self, name: str, kinds: str, cols: int | None = None, n: int | None = None):
        """Dataset ``name``, checked against the schema: dtype kind, (N,) or (N, cols) shape, N == ``n`` if given.

        A float or string column would otherwise be cast silently (a NaN time becomes -2**63) or fail deep inside a command.
        """
        ds = self._need(name)
        want = {"iu": "an integer", "iuf": "a numeric"}[kinds]
        if not isinstance(ds, h5py.Dataset) or ds.dtype.kind not in kinds:
            what = "a group" if not isinstance(ds, h5py.Dataset) else f"dtype {ds.dtype}"
            raise H5FormatError(self.path, f"dataset {name!r} is {what}, expected {want} dtype (see docs/recording_h5.md)")
        shape = (ds.shape[0] if ds.ndim else -1,) + (() if cols is None else (cols,))
        if ds.shape != shape or (n is not None and ds.shape[0] != n):
            expected = f"({'N' if n is None else n},{'' if cols is None else f' {cols}'})"
            raise H5FormatError(self.path, f"dataset {name!r} has shape {ds.shape}, expected {expected}")
        missing = unwritten_problem(ds)
        if missing is not None:
            raise H5FormatError(self.path, f"dataset {name!r} {missing}: the file is damaged or was never finished")
        return ds

    def _load(self) -> None:
        f = self._file
        if f.attrs.get("evpose_format") != FORMAT_NAME:
            raise H5FormatError(self.path, "not an evpose recording (no evpose_format='recording' attribute)")
        try:
            version = int(f.attrs.get("evpose_format_version", 0))
        except (TypeError, ValueError):
            raise H5FormatError(self.path, f"attribute 'evpose_format_version' is {f.attrs['evpose_format_version']!r}, not an integer") from None
        if version > FORMAT_VERSION:
            raise H5FormatError(self.path, f"format version {version} is newer than this evpose reads ({FORMAT_VERSION})")
        t = self._typed("events/t", "iu")
        n = t.shape[0]
        self._cols = {name: self._typed(f"events/{name}", "iu", n=n) for name, _ in _EVENT_COLUMNS}
        idx = self._typed("events/ms_to_idx", "iu")
        self._index = np.asarray(idx[()], dtype=np.int64)
        self._origin = int(idx.attrs.get("t_origin_us", 0))
        if self._index.size == 0 or self._index[-1] != n or self._index[0] != 0 or np.any(np.diff(self._index) < 0):
            raise H5FormatError(self.path, "events/ms_to_idx is inconsistent with the event count")
        self.n_events = int(n)
        if n:
            # The index must span exactly the first to the last event, or windowed reads silently miss events
            # (and a bogus far-future last timestamp would make every command allocate billions of time bins).
            t_first, t_last = int(self._read(t, 0, 1)[0]), int(self._read(t, n - 1, n)[0])
            if t_first < 0:  # the same rule as every other reader's (evpose.io.open.check_nonnegative_times)
                raise H5FormatError(self.path, f"timestamp {t_first} us is negative (event times must be >= 0)", "event 0")
            if t_first != self._origin or t_last < t_first or (t_last - self._origin) // 1000 + 1 != self._index.size - 1:
                raise H5FormatError(self.path, f"events/ms_to_idx (origin {self._origin} us, {self._index.size - 1} ms) does not span the events"
                                    f" ({t_first} .. {t_last} us): the file is damaged or a timestamp is wrong", f"event {n - 1}")
        metadata = self._json_attr("metadata")
        self.metadata: dict = {} if metadata is None else metadata  # `or {}` let an empty JSON list pass as no metadata
        if not isinstance(self.metadata, dict):
            raise H5FormatError(self.path, f"attribute 'metadata' is a JSON {type(self.metadata).__name__}, expected an object")
        cal = self._json_attr("calibration")
        if cal is not None and not isinstance(cal, dict):
            raise H5FormatError(self.path, f"attribute 'calibration' is a JSON {type(cal).__name__}, expected an object")
        self.calibration: CameraCalibration | None = None if cal is None else CameraCalibration.from_dict(cal, source=str(self.path))
        self.imu: ImuSamples | None = None
        if "imu" in f:
            it = self._typed("imu/t", "iu")
            m = it.shape[0]
            self.imu = ImuSamples.from_arrays(self._read(it), self._read(self._typed("imu/acc", "iuf", 3, m)), self._read(self._typed("imu/gyro", "iuf", 3, m)))
        self.ground_truth: Trajectory | None = None
        if "ground_truth" in f:
            g = "ground_truth/"
            gt = self._typed(g + "t", "iu")
            m = gt.shape[0]
            q = self._read(self._typed(g + "quat_xyzw", "iuf", 4, m))
            bad = quaternion_problem(q)
            if bad is not None:
                raise H5FormatError(self.path, bad[1], f"ground-truth pose {bad[0]}")
            self.ground_truth = Trajectory.from_arrays(self._read(gt), self._read(self._typed(g + "position", "iuf", 3, m)), q)

    def _read(self, ds, i0: int | None = None, i1: int | None = None) -> np.ndarray:
        """``ds[i0:i1]``; a chunk that fails to decompress is a damaged file, reported with the rows it holds."""
        try:
            return ds[()] if i0 is None else ds[i0:i1]
        except MemoryError:
            raise H5FormatError(self.path, f"dataset {ds.name.lstrip('/')!r} of shape {ds.shape} does not fit in memory (the file is damaged?)") from None
        except (OSError, RuntimeError, KeyError) as exc:
            if not isinstance(exc, OSError) and hdf5_damage(exc) is None:
                raise
            rows = f"rows {i0}-{i1}" if i0 is not None else None
            raise H5FormatError(self.path, f"cannot read dataset {ds.name.lstrip('/')!r} ({str(exc).split(' (')[-1].rstrip(')')}): the file is damaged", rows) from None

    # ------------------------------------------------------------ lifecycle
    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> "H5RecordingReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------ events
    @property
    def t_start_us(self) -> int:
        return int(self._read(self._cols["t"], 0, 1)[0]) if self.n_events else 0

    @property
    def t_end_us(self) -> int:
        return int(self._read(self._cols["t"], self.n_events - 1, self.n_events)[0]) if self.n_events else 0

    def _locate(self, t0_us: int | None, t1_us: int | None) -> tuple[int, int, np.ndarray]:
        """(i0, i1, t[i0:i1]) for ``t0 <= t < t1``, reading only the timestamps of the bracketing milliseconds."""
        K = self._index.size - 1
        lo, hi = 0, self.n_events
        if t0_us is not None:
            k0 = int(np.clip((int(t0_us) - self._origin) // 1000, 0, K))
            lo = int(self._index[k0])
        if t1_us is not None:
            k1 = int(np.clip(-((self._origin - int(t1_us)) // 1000), 0, K))  # ceil division
            hi = max(lo, int(self._index[k1]))
        t = self._read(self._cols["t"], lo, hi)
        j0 = int(np.searchsorted(t, t0_us, side="left")) if t0_us is not None else 0
        j1 = max(j0, int(np.searchsorted(t, t1_us, side="left")) if t1_us is not None else t.size)
        return lo + j0, lo + j1, t[j0:j1]

    def index_range(self, t0_us: int | None = None, t1_us: int | None = None) -> tuple[int, int]:
        """Event indices ``[i0, i1)`` with ``t0 <= t < t1`` (None = open end)."""
        i0, i1, _ = self._locate(t0_us, t1_us)
        return i0, i1

    def _events(self, i0: int, columns: dict[str, np.ndarray]) -> EventArray:
        """The columns of events ``i0:...`` in the schema's dtypes. A column of another integer dtype (the schema's
        check admits any) is cast only when every value fits: an int32 x of -3 passed the sensor-bounds check (which
        tests x >= width) and the kernels then indexed pixel -3."""
        for name, dtype in _EVENT_COLUMNS:
            col = columns[name]
            if col.dtype != dtype:
                lim = np.iinfo(dtype)
                bad = np.flatnonzero((col < lim.min) | (col > lim.max))
                if bad.size:
                    i = int(bad[0])
                    raise H5FormatError(self.path, f"{name}={col[i]} does not fit the schema's {np.dtype(dtype).name} (see docs/recording_h5.md)",
                                        f"event {i0 + i}")
                columns[name] = col.astype(dtype)
        return EventArray(*(np.ascontiguousarray(columns[c]) for c in "txyp"))

    def read_slice(self, i0: int, i1: int) -> EventArray:
        """Events ``i0:i1`` by index."""
        return self._events(i0, {c: self._read(self._cols[c], i0, i1) for c in "txyp"})

    def read_events(self, t0_us: int | None = None, t1_us: int | None = None) -> EventArray:
        """Events with ``t0 <= t < t1`` (None = open end)."""
        i0, i1, t = self._locate(t0_us, t1_us)
        return self._events(i0, {"t": t, **{c: self._read(self._cols[c], i0, i1) for c in "xyp"}})

    def iter_chunks(self, chunk_events: int = 1 << 22):
        """Yield the events as consecutive batches of at most ``chunk_events``."""
        for i0 in range(0, self.n_events, chunk_events):
            yield self.read_slice(i0, min(self.n_events, i0 + chunk_events))

    def to_recording(self, t0_us: int | None = None, t1_us: int | None = None) -> Recording:
        """A Recording of the window; IMU is windowed on its own clock (``t + time_offset_us``)."""
        imu, gt = self.imu, self.ground_truth
        if t0_us is not None or t1_us is not None:
            lo = np.iinfo(np.int64).min if t0_us is None else int(t0_us)
            hi = np.iinfo(np.int64).max if t1_us is None else int(t1_us)
            off = self.calibration.time_offset_us if self.calibration is not None else 0
            if imu is not None:
                imu = imu.time_window(lo + off if t0_us is not None else lo, hi + off if t1_us is not None else hi)
            if gt is not None:
                gt = gt.time_window(lo, hi)
        return Recording(self.read_events(t0_us, t1_us), imu, gt, self.calibration, dict(self.metadata), source=self.path)


def read_recording_h5(path: str | Path, t0_us: int | None = None, t1_us: int | None = None) -> Recording:
    """Read a whole recording, or the window ``[t0_us, t1_us)`` of it through the time index."""
    with H5RecordingReader(path) as reader:
        return reader.to_recording(t0_us, t1_us)
