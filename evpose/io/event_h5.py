"""Event HDF5 files of TUM-VIE, VECtor and DSEC: ``events/{x,y,t,p}``, optional ``ms_to_idx`` and ``t_offset``.

* ``t`` is in microseconds; ``t_offset`` (a scalar, us) is added when present
  (DSEC, VECtor). ``p`` is 0/1 (or -1/+1, or bool).
* ``ms_to_idx[k]`` is the first event with ``t >= 1000 k`` (before the offset);
  when present it serves windowed reads.
* DSEC/VECtor compress with Blosc/ZSTD, hence ``hdf5plugin``.

Neither file states the sensor size. Sibling files in the same folder fill in
what the dataset layout provides (the first match in sorted order):

* calibration: a basalt JSON (TUM-VIE, ``*calib*.json``: ``value0.intrinsics``
  kb4/pinhole, ``resolution``, ``T_imu_cam``; camera 0 for ``left``, 1 for
  ``right``) or a kalibr YAML (``*.yaml`` with ``cam0``: ``intrinsics``,
  ``distortion_model`` radtan/equidistant, ``distortion_coeffs``,
  ``resolution``, ``T_cam_imu``, ``timeshift_cam_imu``);
* ground truth: ``mocap_data.txt`` (TUM-VIE, ``t_us tx ty tz qx qy qz qw``) or
  a TUM file ``*gt*.txt`` / ``*groundtruth*.txt`` (t in seconds);
* IMU: ``imu_data.txt`` (TUM-VIE: ``t_us gx gy gz ax ay az [temperature]``,
  gyro first, as documented by TUM-VIE readers such as okvis').

Other IMU side files (VECtor's) are not read yet: their column orders differ.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import hdf5plugin  # noqa: F401  (registers Blosc/ZSTD for DSEC and VECtor files)
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.camera import CameraCalibration, DistortionModel
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.errors import InputError
from evpose.io.hdf5_damage import hdf5_damage, unwritten_problem
from evpose.io.text_table import TimeUnit

_BATCH = 1 << 22


class EventH5Error(InputError):
    """An event h5 file that does not follow the TUM-VIE/VECtor/DSEC layout."""


class EventH5Reader:
    """Windowed reads of a TUM-VIE/VECtor/DSEC event file (context manager)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not self.path.is_file():
            raise EventH5Error(self.path, "no such file")
        try:
            self._f = h5py.File(self.path, "r")
        except OSError:
            raise EventH5Error(self.path, "not an HDF5 file") from None
        try:
            g = self._f.get("events")
            if not isinstance(g, h5py.Group):
                raise EventH5Error(self.path, "no 'events' group (expected events/x, events/y, events/t, events/p)")
            missing = [c for c in "xytp" if c not in g]
            if missing:
                raise EventH5Error(self.path, f"missing dataset(s) {', '.join('events/' + c for c in missing)}")
            self._cols = {c: g[c] for c in "txyp"}
            for c, ds in self._cols.items():
                # A string, compound or scalar column ended in a ValueError, TypeError or IndexError traceback.
                if not isinstance(ds, h5py.Dataset) or ds.dtype.kind not in "biuf" or len(ds.shape) != 1:
                    what = "a group" if not isinstance(ds, h5py.Dataset) else f"dtype {ds.dtype}, shape {ds.shape}"
                    raise EventH5Error(self.path, f"events/{c} is {what}, expected a 1-D column of numbers")
            n = self._cols["t"].shape[0]
            if any(ds.shape[0] != n for ds in self._cols.values()):
                raise EventH5Error(self.path, "events/x, y, t, p differ in length")
            for c, ds in self._cols.items():
                missing = unwritten_problem(ds)
                if missing is not None:
                    raise EventH5Error(self.path, f"events/{c} {missing}: the file is damaged or was never finished")
            self.n_events = int(n)
            self.t_offset_us = self._read_t_offset()
            self._ms_to_idx = self._read_ms_to_idx(n) if "ms_to_idx" in self._f else None
            idx = self._ms_to_idx
            if idx is not None and (idx.ndim != 1 or (idx.size and (idx[0] < 0 or idx[-1] > n or np.any(np.diff(idx) < 0)))):
                # Windowed reads trusted it: a reversed or overlong index silently gave wrong windows.
                raise EventH5Error(self.path, f"ms_to_idx is not a non-decreasing index into the {n} events (the file is damaged)")
        except BaseException as exc:
            self._f.close()
            damage = hdf5_damage(exc)
            if damage is not None:  # a damaged object header or symbol table (see hdf5_damage)
                raise EventH5Error(self.path, f"the file's HDF5 structure is damaged ({damage})") from None
            raise

    def close(self) -> None:
        self._f.close()

    def __enter__(self) -> "EventH5Reader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _read_ms_to_idx(self, n: int) -> np.ndarray:
        """``ms_to_idx`` as int64; a float one holding NaN printed numpy's "invalid value encountered in cast"."""
        ds = self._f["ms_to_idx"]
        raw = np.asarray(ds[()]) if isinstance(ds, h5py.Dataset) else np.zeros((0, 0))
        if raw.dtype.kind not in "iuf" or (raw.dtype.kind == "f" and not (np.isfinite(raw).all() and (raw == np.round(raw)).all())):
            raise EventH5Error(self.path, f"ms_to_idx is not a non-decreasing index into the {n} events (the file is damaged)")
        return raw.astype(np.int64)

    def _read_t_offset(self) -> int:
        """``t_offset`` in us (0 if absent): a NaN one ended in a ValueError traceback, an array silently gave its first value."""
        if "t_offset" not in self._f:
            return 0
        ds = self._f["t_offset"]
        values = np.asarray(ds[()]).reshape(-1) if isinstance(ds, h5py.Dataset) else np.zeros(0)
        if values.size != 1 or values.dtype.kind not in "iuf" or not np.isfinite(values[0]):
            got = repr(values[0].item()) if values.size == 1 else f"{values.size} values" if isinstance(ds, h5py.Dataset) else "a group"
            raise EventH5Error(self.path, f"t_offset must be one finite number of microseconds, got {got}")
        return int(values[0])

    def _times(self, i0: int, i1: int) -> np.ndarray:
        """Absolute times (int64 us) of events ``i0:i1``; a NaN in a float column was cast to -2**63 (with numpy's
        RuntimeWarning) and reported as 'earlier than the previous -9223372036854775808 us'."""
        t = self._cols["t"][i0:i1]
        if t.dtype.kind == "f" and not np.isfinite(t).all():
            i = int(np.flatnonzero(~np.isfinite(t))[0])
            raise EventH5Error(self.path, f"timestamp {t[i]} is not a finite number", f"event {i0 + i}")
        return t.astype(np.int64) + self.t_offset_us

    def read_slice(self, i0: int, i1: int) -> EventArray:
        t = self._times(i0, i1)
        p = self._cols["p"][i0:i1]
        if p.size and not np.all((p == 0) | (p == 1) | (p == -1)):
            i = int(np.flatnonzero(~((p == 0) | (p == 1) | (p == -1)))[0])
            raise EventH5Error(self.path, f"polarity {p[i]} is not 0/1 or -1/+1", f"event {i0 + i}")
        x = self._cols["x"][i0:i1]
        y = self._cols["y"][i0:i1]
        for name, col in (("x", x), ("y", y)):
            # A float column of 3.7 was truncated to pixel 3, a NaN cast to 0 with numpy's warning on stderr.
            bad = (col < 0) | (col > 65535) if col.dtype.kind != "f" else ~((col >= 0) & (col <= 65535) & (col == np.floor(col)))
            if col.size and bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise EventH5Error(self.path, f"{name}={col[i]} is not a pixel coordinate", f"event {i0 + i}")
        return EventArray(t, x.astype(np.uint16), y.astype(np.uint16), np.where(p > 0, 1, -1).astype(np.int8))

    def index_range(self, t0_us: int, t1_us: int) -> tuple[int, int]:
        """Indices of events with ``t0 <= t < t1`` (absolute us), narrowed by ``ms_to_idx`` when present."""
        lo, hi = 0, self.n_events
        if self._ms_to_idx is not None and self._ms_to_idx.size:
            K = self._ms_to_idx.size - 1
            k0 = int(np.clip((t0_us - self.t_offset_us) // 1000, 0, K))
            k1 = int(np.clip(-((self.t_offset_us - t1_us) // 1000) + 1, 0, K))
            lo = int(self._ms_to_idx[k0])
            hi = self.n_events if k1 >= K else max(lo, int(self._ms_to_idx[k1]))
        t = self._times(lo, hi)
        return lo + int(np.searchsorted(t, t0_us, "left")), lo + int(np.searchsorted(t, t1_us, "left"))

    def read_events(self, t0_us: int, t1_us: int) -> EventArray:
        return self.read_slice(*self.index_range(t0_us, t1_us))


# ------------------------------------------------------------------ siblings
def _camera_index(path: Path) -> int:
    return 1 if "right" in path.name.lower() else 0


def _require_file(path: Path) -> None:
    """A sibling file found by name must be a regular file: reading a named pipe waited for a writer forever."""
    if not path.is_file():
        from evpose.io.paths import not_a_file

        raise InputError(path, not_a_file(path))


def _basalt_calibration(path: Path, cam: int) -> CameraCalibration:
    _require_file(path)
    try:
        d = json.loads(path.read_text(encoding="utf-8"))["value0"]
        intr = d["intrinsics"][cam]
        kind = intr["camera_type"]
        v = intr["intrinsics"]
        w, h = (int(a) for a in d["resolution"][cam])
        if kind == "kb4":
            model, dist = DistortionModel.EQUIDISTANT, (v["k1"], v["k2"], v["k3"], v["k4"])
        elif kind == "pinhole":
            model, dist = DistortionModel.NONE, ()
        else:
            raise InputError(path, f"unsupported camera_type {kind!r} (kb4 or pinhole)")
        T_imu_cam = np.eye(4)
        if "T_imu_cam" in d:
            e = d["T_imu_cam"][cam]
            T_imu_cam[:3, :3] = Rotation.from_quat([e["qx"], e["qy"], e["qz"], e["qw"]]).as_matrix()
            T_imu_cam[:3, 3] = [e["px"], e["py"], e["pz"]]
        T_cam_imu = np.linalg.inv(T_imu_cam)
        return CameraCalibration(w, h, v["fx"], v["fy"], v["cx"], v["cy"], model, dist, T_cam_imu)
    except InputError as exc:  # CameraCalibration's own checks name no file
        raise InputError(exc.path or path, exc.problem, exc.record) from None
    except OSError as exc:  # e.g. a folder named calib.json: an IsADirectoryError traceback
        raise InputError(path, f"cannot read the calibration ({exc.strerror})") from None
    except (KeyError, IndexError, TypeError, ValueError, OverflowError) as exc:
        raise InputError(path, f"not a basalt calibration ({type(exc).__name__}: {exc})") from None


def _kalibr_calibration(path: Path, cam: int) -> CameraCalibration | None:
    import yaml

    _require_file(path)
    try:
        d = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(path, f"cannot read the calibration ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(path, "not a text file (a kalibr calibration is YAML)") from None
    except yaml.YAMLError as exc:
        # The parser's report quotes the file over several lines: its problem and line, as for config files.
        mark = getattr(exc, "problem_mark", None)
        raise InputError(path, f"not valid YAML ({getattr(exc, 'problem', None) or str(exc).splitlines()[0]})",
                         f"line {mark.line + 1}" if mark is not None else None) from None
    key = f"cam{cam}"
    if not isinstance(d, dict) or key not in d:
        return None
    c = d[key]
    try:
        fx, fy, cx, cy = (float(v) for v in c["intrinsics"])
        w, h = (int(v) for v in c["resolution"])
        dm = str(c.get("distortion_model", "none")).lower()
        coeffs = [float(v) for v in c.get("distortion_coeffs", [])]
        if dm == "radtan":
            if len(coeffs) not in (4, 5):
                raise InputError(path, f"radtan needs 4 or 5 distortion_coeffs, got {len(coeffs)}", key)
            model, dist = DistortionModel.RADTAN, tuple((coeffs + [0.0])[:5])
        elif dm == "equidistant":
            if len(coeffs) != 4:
                raise InputError(path, f"equidistant needs 4 distortion_coeffs, got {len(coeffs)}", key)
            model, dist = DistortionModel.EQUIDISTANT, tuple(coeffs)
        elif dm == "none" or not any(coeffs):
            model, dist = DistortionModel.NONE, ()
        else:
            raise InputError(path, f"unsupported distortion_model {dm!r}", key)
        T = np.asarray(c.get("T_cam_imu", np.eye(4)), dtype=np.float64).reshape(4, 4)
        offset = int(round(float(c.get("timeshift_cam_imu", 0.0)) * 1e6))
        return CameraCalibration(w, h, fx, fy, cx, cy, model, dist, T, offset)
    except InputError as exc:  # CameraCalibration's own checks name no file
        raise InputError(exc.path or path, exc.problem, exc.record or key) from None
    except (KeyError, TypeError, ValueError, OverflowError) as exc:  # OverflowError: timeshift_cam_imu .inf
        raise InputError(path, f"not a kalibr camera calibration ({type(exc).__name__}: {exc})", key) from None


def find_sibling_calibration(path: Path) -> tuple[CameraCalibration | None, Path | None]:
    cam = _camera_index(path)
    for cand in sorted(path.parent.glob("*calib*.json")):
        return _basalt_calibration(cand, cam), cand
    for cand in sorted(list(path.parent.glob("*.yaml")) + list(path.parent.glob("*.yml"))):
        cal = _kalibr_calibration(cand, cam)
        if cal is not None:
            return cal, cand
    return None, None


def sibling_files(path: Path) -> list[Path]:
    """The files next to the event file that the ``find_sibling_*`` readers may read (all kalibr YAML candidates)."""
    folder = path.parent
    calib = sorted(folder.glob("*calib*.json"))[:1] or sorted(list(folder.glob("*.yaml")) + list(folder.glob("*.yml")))
    gt = [folder / "mocap_data.txt"] if (folder / "mocap_data.txt").is_file() else []
    for pattern in ("*groundtruth*.txt", "*gt*.txt"):
        gt = gt or sorted(folder.glob(pattern))[:1]
    imu = [folder / "imu_data.txt"] if (folder / "imu_data.txt").is_file() else []
    return calib + gt + imu


def find_sibling_ground_truth(path: Path):
    from evpose.io.tum import read_tum

    mocap = path.parent / "mocap_data.txt"
    if mocap.exists():  # read_table names a folder in its place (it was skipped: no ground truth, silently)
        return read_tum(mocap, unit=TimeUnit.MICROSECONDS), mocap
    for pattern in ("*groundtruth*.txt", "*gt*.txt"):
        for cand in sorted(path.parent.glob(pattern)):
            return read_tum(cand), cand
    return None, None


def find_sibling_imu(path: Path):
    """TUM-VIE ``imu_data.txt`` next to the event file: (ImuSamples, path) or (None, None)."""
    from evpose.core.imu import ImuSamples
    from evpose.io.text_table import read_table

    cand = path.parent / "imu_data.txt"
    if not cand.exists():
        return None, None
    _require_file(cand)  # a folder was skipped: a recording without its IMU
    n_cols = 8
    with open(cand, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if line.strip() and not line.lstrip().startswith("#"):
                n_cols = 7 if len(line.split()) == 7 else 8
                break
    t, v = read_table(cand, n_cols, unit=TimeUnit.MICROSECONDS)
    if t.size == 0:
        raise InputError(cand, "contains no IMU samples")
    return ImuSamples.from_arrays(t, v[:, 3:6], v[:, 0:3]), cand


def open_event_h5_stream(path: str | Path, width: int | None = None, height: int | None = None):
    """A :class:`~evpose.io.open.RecordingStream` over an event h5 file and its sibling calibration / ground truth."""
    from evpose.io.open import RecordingStream, SourceFormat, check_events

    path = Path(path)
    with EventH5Reader(path) as r:
        n, offset = r.n_events, r.t_offset_us
    cal, cal_path = find_sibling_calibration(path)
    gt, gt_path = find_sibling_ground_truth(path)
    imu, imu_path = find_sibling_imu(path)
    metadata = {"source_format": "event-h5", "t_offset_us": offset}
    if imu_path is not None:
        metadata["imu_file"] = imu_path.name
    if cal_path is not None:
        metadata["calibration_file"] = cal_path.name
    if gt_path is not None:
        metadata["ground_truth_file"] = gt_path.name
    if width is not None and height is not None:
        from evpose.io.open import check_size_flags

        check_size_flags(path, None if cal is None else (cal.width, cal.height), width, height, f"the calibration {cal_path.name if cal_path else ''}")
        if cal is None:
            metadata["width"], metadata["height"] = int(width), int(height)
    ctx = Recording(EventArray.empty(), imu, gt, cal, metadata, source=path)
    size = ctx.sensor_size
    if n == 0:
        raise EventH5Error(path, "contains no events")

    def batches(on_progress=None):
        last = None
        with EventH5Reader(path) as reader:
            for i0 in range(0, reader.n_events, _BATCH):
                b = reader.read_slice(i0, min(reader.n_events, i0 + _BATCH))
                check_events(b, i0, last, size, path)
                last = int(b.t[-1])
                if on_progress is not None:
                    on_progress(len(b))
                yield b

    return RecordingStream(ctx, SourceFormat.EVENT_H5, batches, n, "ev")


def write_event_h5(path: str | Path, events: EventArray, t_offset_us: int = 0, with_ms_to_idx: bool = True, compression=None) -> None:
    """Write a DSEC-style event file (for tests, benchmarks and exporting): t relative to ``t_offset``, p 0/1."""
    from evpose.io.atomic import atomic_path

    comp = {} if compression is None else dict(compression)
    t_rel = events.t - t_offset_us
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as f:
        g = f.create_group("events")
        g.create_dataset("x", data=events.x, chunks=True if len(events) else None, **comp)
        g.create_dataset("y", data=events.y, chunks=True if len(events) else None, **comp)
        g.create_dataset("t", data=t_rel.astype(np.int64), chunks=True if len(events) else None, **comp)
        g.create_dataset("p", data=(events.p > 0).astype(np.uint8), chunks=True if len(events) else None, **comp)
        f.create_dataset("t_offset", data=np.int64(t_offset_us))
        if with_ms_to_idx:
            kmax = int(t_rel[-1] // 1000) + 1 if len(events) else 0
            f.create_dataset("ms_to_idx", data=np.searchsorted(t_rel, 1000 * np.arange(kmax + 1), "left").astype(np.uint64))
