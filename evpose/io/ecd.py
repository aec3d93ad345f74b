"""Event Camera Dataset (ECD) text folders: ``events.txt``, ``imu.txt``, ``groundtruth.txt``, ``calib.txt``.

* ``events.txt``: ``t x y p`` per line, t in seconds, p 0/1 (also -1/1 accepted).
* ``imu.txt``: ``t ax ay az gx gy gz`` (s, m/s^2, rad/s).
* ``groundtruth.txt``: ``t px py pz qx qy qz qw`` (s, m, ``T_world_cam``).
* ``calib.txt``: ``fx fy cx cy k1 k2 p1 p2 k3`` (radtan; 4 values = no distortion).

ECD files do not state the sensor size, and the largest pixel seen is not a
sensor size, so the size comes from the caller (``width``/``height``, e.g.
240x180 for the DAVIS240C) or from the ``evpose.json`` sidecar that
:func:`write_ecd_folder` adds (it also carries metadata and the full
calibration, so our own folders round-trip losslessly). Without a size the
calibration stays ``None`` and ``calib.txt``'s values go to
``metadata["ecd_calib_txt"]``.

With both, the sidecar's calibration is the one used (it also holds the sensor size, the extrinsic and models
``calib.txt`` cannot state), but ``calib.txt`` is still read and must be sound and agree with it to the precision
its values are written with: it is the file an ECD user edits, and a damaged or edited ``calib.txt`` beside the
sidecar was silently ignored.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from evpose.core.camera import CameraCalibration, DistortionModel
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording, metadata_sensor_size
from evpose.core.trajectory import Trajectory, quaternion_problem
from evpose.errors import InputError
from evpose.io import ecd_text
from evpose.io.atomic import atomic_path
from evpose.io.text_table import read_table, write_table

EVENTS_FILE = "events.txt"
IMU_FILE = "imu.txt"
GT_FILE = "groundtruth.txt"
CALIB_FILE = "calib.txt"
SIDECAR_FILE = "evpose.json"
DEFAULT_BLOCK_BYTES = 32 << 20


def is_ecd_folder(path: str | Path) -> bool:
    path = Path(path)
    return path.is_dir() and (path / EVENTS_FILE).is_file()


_WRITTEN_FILES = frozenset({EVENTS_FILE, IMU_FILE, GT_FILE, CALIB_FILE, SIDECAR_FILE})


def check_ecd_target(folder: str | Path) -> None:
    """Refuse to write an ECD folder over an existing folder that holds anything but an ECD recording's files.

    The folder is replaced whole (atomically): ``evpose simulate --out some_folder`` deleted every file in it.
    """
    folder = Path(folder)
    if not folder.is_dir():
        return
    foreign = sorted(p.name for p in folder.iterdir() if p.name not in _WRITTEN_FILES)
    if foreign:
        more = f" and {len(foreign) - 1} more" if len(foreign) > 1 else ""
        raise InputError(folder, f"refusing to replace a folder that is not an ECD recording (it holds {foreign[0]!r}{more});"
                         " give a new folder name, or a path ending in .h5")


def _line_text(buf: np.ndarray, start: int, n_bytes: int) -> str:
    end = start
    while end < n_bytes and buf[end] != 10 and end - start < 80:
        end += 1
    return bytes(buf[start:end]).decode("utf-8", "replace").strip()


def iter_ecd_events(
    path: str | Path,
    width: int | None = None,
    height: int | None = None,
    block_bytes: int = DEFAULT_BLOCK_BYTES,
    on_bytes: Callable[[int], None] | None = None,
) -> Iterator[EventArray]:
    """Stream ``events.txt`` as EventArray blocks of about ``block_bytes`` of text each.

    Memory stays bounded by the block size. Every line is checked; the first
    bad one raises :class:`InputError` with its line number. ``on_bytes(n)``
    reports progress in bytes read. An empty file is an error.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such file")
    w = -1 if width is None else int(width)
    h = -1 if height is None else int(height)
    buf = np.empty(block_bytes + 1, dtype=np.uint8)
    # A text line holds at least 8 bytes ("0 0 0 0\n"), so this bounds the events per block.
    cap = block_bytes // 8 + 1
    pow10 = ecd_text.pow10_table()
    last_t = np.iinfo(np.int64).min
    lines_before = 0
    carry = 0  # bytes of an incomplete line kept at the start of buf
    total = 0
    with open(path, "rb") as fh:
        eof = False
        while not eof:
            view = memoryview(buf)[carry:block_bytes]
            got = fh.readinto(view)
            if on_bytes is not None and got:
                on_bytes(got)
            n_bytes = carry + got
            if got == 0:
                eof = True
                if carry == 0:
                    break
                buf[n_bytes] = 10  # terminate a last line without newline
                n_bytes += 1
            # Fresh outputs per block (untouched pages cost nothing), so blocks are yielded without a copy.
            out_t, out_x, out_y, out_p = np.empty(cap, np.int64), np.empty(cap, np.uint16), np.empty(cap, np.uint16), np.empty(cap, np.int8)
            n, used, lines, err, last_t = ecd_text.parse_event_lines(buf, n_bytes, out_t, out_x, out_y, out_p, last_t, w, h, pow10)
            if err != ecd_text.ERR_OK:
                line = _line_text(buf, used, n_bytes)
                raise InputError(path, f"{ecd_text.MESSAGES[err]} ({line!r})", f"line {lines_before + lines}")
            if used == 0 and n_bytes >= block_bytes:
                raise InputError(path, f"a line longer than {block_bytes} bytes", f"line {lines_before + 1}")
            lines_before += lines
            carry = n_bytes - used
            if carry:
                buf[:carry] = buf[used:n_bytes]
            if n:
                total += n
                yield EventArray(out_t[:n], out_x[:n], out_y[:n], out_p[:n])
    if total == 0:
        raise InputError(path, "contains no events")


def read_ecd_events(path: str | Path, width: int | None = None, height: int | None = None) -> EventArray:
    """All of ``events.txt`` in memory."""
    return EventArray.concatenate(list(iter_ecd_events(path, width, height)))


def read_ecd_calib(path: str | Path) -> list[float]:
    """The raw values of ``calib.txt`` (4 or 9 finite numbers)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(path, f"cannot read ({exc})") from None
    words = text.split()
    if len(words) not in (4, 9):
        raise InputError(path, f"expected 9 values 'fx fy cx cy k1 k2 p1 p2 k3' (or 4 without distortion), got {len(words)}")
    try:
        vals = [float(v) for v in words]
    except ValueError:
        raise InputError(path, "calibration value is not a number") from None
    if not all(np.isfinite(vals)):
        raise InputError(path, "NaN or infinite calibration value")
    return vals


def calibration_from_ecd(vals: list[float], width: int, height: int, source: str | None = None) -> CameraCalibration:
    fx, fy, cx, cy = vals[:4]
    dist = tuple(vals[4:])
    model = DistortionModel.RADTAN if dist and any(dist) else DistortionModel.NONE
    try:
        return CameraCalibration(int(width), int(height), fx, fy, cx, cy, model, dist if model is DistortionModel.RADTAN else ())
    except InputError as exc:
        raise InputError(source, exc.problem) from None


_CALIB_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3")


def _printed_tolerance(word: str) -> float:
    """Half a unit in the last digit ``word`` was written with ("247.07" -> 0.005, "-3.68e-1" -> 0.0005): a value
    rounded for print agrees with the exact one. A zero is exact ("0 0 0 0 0" is how ``calib.txt`` says "no
    distortion")."""
    m = re.fullmatch(r"[+-]?(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?", word.strip())
    if m is None or float(word) == 0.0:
        return 0.0
    return 0.5 * 10.0 ** (int(m.group(3) or 0) - len(m.group(2) or ""))


def check_calib_agrees(calib_path: Path, calibration: CameraCalibration) -> None:
    """Raise :class:`InputError` naming ``calib.txt`` when it is damaged, or when its values differ from the sidecar's
    ``calibration`` (the one used) by more than their printed precision: the intrinsics always, the distortion where
    the sidecar's model is one ``calib.txt`` states (radtan, none)."""
    vals = read_ecd_calib(calib_path)
    words = calib_path.read_text(encoding="utf-8").split()
    ours = [calibration.fx, calibration.fy, calibration.cx, calibration.cy]
    if calibration.model in (DistortionModel.RADTAN, DistortionModel.NONE):
        ours += list(calibration.dist) if calibration.model is DistortionModel.RADTAN else [0.0] * 5
    elif any(vals[4:]):
        raise InputError(calib_path, f"states a radtan distortion, but the calibration in {SIDECAR_FILE}, which is the one used,"
                         f" is {calibration.model.value}: make them agree (or delete one of them)")
    theirs = list(vals) + [0.0] * (len(ours) - len(vals))  # 4 values: no distortion
    tolerance = [_printed_tolerance(w) for w in words] + [0.0] * (len(ours) - len(words))
    for name, a, b, tol in zip(_CALIB_NAMES, theirs, ours, tolerance):
        if abs(a - b) > tol + 1e-9 * max(abs(a), abs(b), 1.0):
            raise InputError(calib_path, f"{name} {a!r} contradicts the calibration in {SIDECAR_FILE} ({name} {b!r}), which is the"
                             f" one used: make them agree (or delete one of them)")


def read_ecd_sidecar(folder: Path) -> dict:
    path = folder / SIDECAR_FILE
    if path.is_dir():  # skipped, it gave a recording without its calibration
        raise InputError(path, "is a folder, not a file")
    if not path.is_file():
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise InputError(path, f"not valid JSON ({exc})") from None
    if not isinstance(data, dict):
        raise InputError(path, "expected a JSON object")
    return data


def _checked_by_line(validate, path: Path, lines: list[int], record: str) -> None:
    """Run a stream's ``validate`` naming its text file and line: the checks after parsing (an acceleration beyond any
    IMU's, a position beyond the Earth) named the folder and a 0-based sample index."""
    try:
        validate(source=str(path))
    except InputError as exc:
        if exc.record and exc.record.startswith(record) and exc.record[len(record):].isdigit():
            raise InputError(path, exc.problem, f"line {lines[int(exc.record[len(record):])]}") from None
        raise


def read_ecd_context(folder: str | Path, width: int | None = None, height: int | None = None) -> tuple[Recording, tuple[int, int] | None]:
    """Everything but the events: (Recording with empty events, sensor size or None)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(folder, "no such folder")
    if not (folder / EVENTS_FILE).is_file():
        raise InputError(folder / EVENTS_FILE, "no such file (an ECD folder needs events.txt)")
    side = read_ecd_sidecar(folder)
    if not isinstance(side.get("metadata", {}), dict):  # dict(5) was a TypeError traceback in every command
        raise InputError(folder / SIDECAR_FILE, f"expected a JSON object, got {type(side['metadata']).__name__}", "metadata")
    metadata = dict(side.get("metadata", {}))
    if not side:
        metadata["source_format"] = "ecd"  # our own folders keep their metadata exactly
    calibration = None
    if side.get("calibration") is not None:
        calibration = CameraCalibration.from_dict(side["calibration"], source=str(folder / SIDECAR_FILE))
    size = None
    if width is not None and height is not None:
        from evpose.io.open import check_size_flags

        if calibration is not None:
            check_size_flags(folder / SIDECAR_FILE, (calibration.width, calibration.height), width, height, "its calibration")
        elif "width" in metadata and "height" in metadata:
            check_size_flags(folder / SIDECAR_FILE, metadata_sensor_size(metadata, folder / SIDECAR_FILE), width, height, "its metadata")
        size = (int(width), int(height))
    elif calibration is not None:
        size = (calibration.width, calibration.height)
    elif "width" in metadata and "height" in metadata:
        size = metadata_sensor_size(metadata, folder / SIDECAR_FILE)
    if size is not None and (size[0] <= 0 or size[1] <= 0):
        raise InputError(folder, f"sensor size must be positive, got {size[0]}x{size[1]}")
    calib_path = folder / CALIB_FILE
    if calib_path.is_dir():
        raise InputError(calib_path, "is a folder, not a file")
    if calibration is not None and calib_path.is_file():
        check_calib_agrees(calib_path, calibration)
    elif calib_path.is_file():
        vals = read_ecd_calib(calib_path)
        if size is not None:
            calibration = calibration_from_ecd(vals, *size, source=str(calib_path))
        else:
            metadata["ecd_calib_txt"] = vals
    if size is not None and calibration is None:
        metadata["width"], metadata["height"] = size
    imu = None
    if (folder / IMU_FILE).exists():  # read_table names a folder in its place (it was skipped: no IMU, silently)
        lines: list[int] = []
        t, v = read_table(folder / IMU_FILE, 7, line_numbers=lines)
        if t.size == 0:
            raise InputError(folder / IMU_FILE, "contains no IMU samples")
        imu = ImuSamples.from_arrays(t, v[:, 0:3], v[:, 3:6])
        _checked_by_line(imu.validate, folder / IMU_FILE, lines, "IMU sample ")
    gt = None
    if (folder / GT_FILE).exists():
        lines = []
        t, v = read_table(folder / GT_FILE, 8, line_numbers=lines)
        if t.size == 0:
            raise InputError(folder / GT_FILE, "contains no poses")
        bad = quaternion_problem(v[:, 3:7])
        if bad is not None:
            raise InputError(folder / GT_FILE, bad[1], f"line {lines[bad[0]]}")
        gt = Trajectory.from_arrays(t, v[:, 0:3], v[:, 3:7])
        _checked_by_line(gt.validate, folder / GT_FILE, lines, "pose ")
    rec = Recording(EventArray.empty(), imu, gt, calibration, metadata, source=folder)
    return rec, size


def read_ecd_folder(folder: str | Path, width: int | None = None, height: int | None = None) -> Recording:
    """Read an ECD folder into memory; ``width``/``height`` state the sensor size (else sidecar, else unknown)."""
    rec, size = read_ecd_context(folder, width, height)
    w, h = size if size else (None, None)
    rec.events = read_ecd_events(Path(folder) / EVENTS_FILE, w, h)
    return rec


def write_ecd_events(path: Path, events: EventArray, block: int = 1 << 20) -> None:
    """Write events as ECD text in blocks (numba formatter; no per-event Python objects)."""
    buf = np.empty(48 * min(block, max(len(events), 1)), dtype=np.uint8)
    with open(path, "wb") as fh:
        for i0 in range(0, len(events), block):
            ev = events[i0 : i0 + block]
            n = ecd_text.format_event_lines(ev.t, ev.x, ev.y, ev.p, buf)
            fh.write(memoryview(buf)[:n])


def write_ecd_folder(folder: str | Path, recording: Recording) -> None:
    """Write ``recording`` as an ECD folder, atomically (the folder appears complete or not at all).

    ``calib.txt`` is written for radtan / undistorted calibrations; the
    ``evpose.json`` sidecar keeps the full calibration, sensor size and metadata.
    """
    inputs = (recording.source,) if recording.source is not None else ()
    check_ecd_target(folder)
    with atomic_path(folder, inputs=inputs, is_dir=True) as tmp:
        write_ecd_events(tmp / EVENTS_FILE, recording.events)
        if recording.imu is not None:
            with open(tmp / IMU_FILE, "w", encoding="utf-8") as fh:
                write_table(fh, recording.imu.t, np.hstack([recording.imu.acc, recording.imu.gyro]))
        if recording.ground_truth is not None:
            gt = recording.ground_truth
            with open(tmp / GT_FILE, "w", encoding="utf-8") as fh:
                write_table(fh, gt.t, np.hstack([gt.position, gt.quat_xyzw]))
        cal = recording.calibration
        if cal is not None and cal.model in (DistortionModel.RADTAN, DistortionModel.NONE):
            dist = cal.dist if cal.model is DistortionModel.RADTAN else (0.0,) * 5
            (tmp / CALIB_FILE).write_text(" ".join(repr(float(v)) for v in (cal.fx, cal.fy, cal.cx, cal.cy, *dist)) + "\n", encoding="utf-8")
        side = {"metadata": recording.metadata, "calibration": cal.to_dict() if cal is not None else None}
        (tmp / SIDECAR_FILE).write_text(json.dumps(side, indent=1, sort_keys=True) + "\n", encoding="utf-8")
