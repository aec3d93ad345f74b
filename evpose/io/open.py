"""Recognise a recording on disk and open it: ECD folder, evpose HDF5, event h5, ROS1/ROS2 bag.

:func:`open_stream` gives everything except the events in memory plus a
generator of event batches, so :mod:`evpose.io.convert` can stream any source
with bounded memory; :func:`open_recording` reads it all.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator

from evpose.core.events import EventArray, check_span
from evpose.core.recording import Recording
from evpose.errors import ConfigError, InputError


class SourceFormat(str, enum.Enum):
    """Formats :func:`detect_format` recognises."""

    ECD = "ecd"
    EVPOSE_H5 = "evpose-h5"
    EVENT_H5 = "event-h5"
    ROS1_BAG = "ros1-bag"
    ROS2_BAG = "ros2-bag"


@dataclass
class RecordingStream:
    """A recording whose events are read batch by batch."""

    context: Recording
    """Calibration, IMU, ground truth and metadata; ``events`` is empty."""
    format: SourceFormat
    """What the source was recognised as."""
    batches: Callable[[Callable[[int], None] | None], Iterator[EventArray]]
    """``batches(on_progress)`` yields the events in time order; ``on_progress(n)`` advances by ``n`` progress units."""
    progress_total: int
    """Progress units in the whole source (bytes or events)."""
    progress_unit: str
    """``"B"`` or ``"ev"``."""


def check_events(ev: EventArray, offset: int, last_t: int | None, size: tuple[int, int] | None, source: str | Path, record: str = "event") -> None:
    """Validate one batch whose first event has global index ``offset``; errors name ``{record} {index}``."""
    try:
        ev.validate(*(size if size else (None, None)), source=str(source))
    except InputError as exc:
        i = int(exc.record.split()[-1]) if exc.record else 0
        raise InputError(source, exc.problem, f"{record} {offset + i}") from None
    if last_t is not None and len(ev) and int(ev.t[0]) < last_t:
        raise InputError(source, f"timestamp {int(ev.t[0])} us is earlier than the previous {last_t} us (timestamps must be sorted)", f"{record} {offset}")


def check_nonnegative_times(ev: EventArray, source: str | Path | None, offset: int = 0, record: str = "event") -> None:
    """Event times are microseconds since the recording's origin: a negative one is a broken conversion or clock
    (it puts the events before the IMU and ground truth, and the tracker then runs no update at all)."""
    if len(ev) and int(ev.t[0]) < 0:  # sorted, so the first is the smallest
        raise InputError(source, f"timestamp {int(ev.t[0])} us is negative (event times must be >= 0)", f"{record} {offset}")


def _is_hdf5(path: Path) -> bool:
    try:
        with open(path, "rb") as fh:
            return fh.read(8) == b"\x89HDF\r\n\x1a\n"
    except PermissionError:
        raise  # "not an HDF5 file (bad signature)" misled about a file the user may not read
    except OSError:
        return False


def detect_format(path: str | Path) -> SourceFormat:
    """What ``path`` holds, from its layout and magic bytes (not just its suffix)."""
    from evpose.io import ecd, h5

    path = Path(path)
    if not path.exists():
        raise InputError(path, "no such file or folder")
    if path.is_dir():
        if ecd.is_ecd_folder(path):
            return SourceFormat.ECD
        if (path / "metadata.yaml").is_file() or any(path.glob("*.db3")) or any(path.glob("*.mcap")):
            return SourceFormat.ROS2_BAG
        raise InputError(path, "folder is neither an ECD folder (events.txt) nor a ROS2 bag (metadata.yaml)")
    if not path.is_file():
        # Reading a named pipe's magic bytes waited for a writer forever.
        raise InputError(path, "is not a regular file (a pipe, device or socket); a recording is a file or a folder")
    suffix = path.suffix.lower()
    if ecd.is_ecd_folder(path.parent) and path.parent / ecd.EVENTS_FILE == path:
        # `info` takes events.txt for its folder; the other commands called it an "unrecognised recording".
        raise InputError(path, f"an ECD recording is its folder (events.txt, imu.txt...): give {path.parent}")
    if suffix == ".bag":
        return SourceFormat.ROS1_BAG
    if suffix in (".db3", ".mcap"):
        return SourceFormat.ROS2_BAG
    if _is_hdf5(path):
        return SourceFormat.EVPOSE_H5 if h5.is_recording_h5(path) else SourceFormat.EVENT_H5
    if suffix in (".h5", ".hdf5"):
        raise InputError(path, "not an HDF5 file (bad signature)")
    raise InputError(path, f"unrecognised recording (suffix {suffix!r}); expected an ECD folder, .h5/.hdf5, .bag, ROS2 bag folder, .db3 or .mcap")


def recording_files(path: str | Path) -> list[Path]:
    """The files besides ``path`` itself that a recording at ``path`` is read from: an ECD folder's text files and
    sidecar, a ROS2 bag folder's metadata and storage files, an event h5's sibling calibration, ground truth and IMU.
    Outputs must never replace them (``evpose.io.atomic``); anything else gives []."""
    from evpose.io import ecd

    path = Path(path)
    if path.is_dir():
        names = (ecd.EVENTS_FILE, ecd.IMU_FILE, ecd.GT_FILE, ecd.CALIB_FILE, ecd.SIDECAR_FILE, "metadata.yaml")
        return [path / n for n in names if (path / n).is_file()] + sorted(path.glob("*.db3")) + sorted(path.glob("*.mcap"))
    if path.suffix.lower() in (".h5", ".hdf5") and path.is_file() and _is_hdf5(path):
        from evpose.io import event_h5, h5

        return [] if h5.is_recording_h5(path) else event_h5.sibling_files(path)
    return []


def open_stream(path: str | Path, width: int | None = None, height: int | None = None, **options) -> RecordingStream:
    """Open ``path`` for streaming. ``width``/``height`` state the sensor size where the format lacks it.

    ``options`` go to the format's reader (bag topics: ``events_topic``, ``imu_topic``, ``pose_topic``).
    The IMU and ground truth are checked here (the event batches as they stream), so no command, ``convert``
    included, passes on a NaN or an unsorted sample.
    """
    stream = _open_stream(path, width, height, **options)
    for small in (stream.context.imu, stream.context.ground_truth):
        if small is not None:
            small.validate(source=str(path))
    inner = stream.batches

    def batches(cb=None):
        t_first, offset = None, 0
        for b in inner(cb):
            if t_first is None and len(b):
                check_nonnegative_times(b, path)  # batches are sorted: the first event is the earliest
                t_first = int(b.t[0])
            check_span(b.t, path, offset, t_first)  # `info` described a stray event 11 days on as the recording's end
            offset += len(b)
            yield b

    stream.batches = batches
    return stream


def check_size_flags(path: Path, stated: tuple[int, int] | None, width: int | None, height: int | None, by: str) -> None:
    """Refuse ``--width/--height`` that contradict the sensor size a recording states (``by`` says where): the
    flags are for formats that do not state it, and silently preferring either side tracks with a wrong image size."""
    if width is None or height is None or stated is None:
        return
    if (int(stated[0]), int(stated[1])) != (int(width), int(height)):
        raise InputError(path, f"--width/--height {width}x{height} contradict the {stated[0]}x{stated[1]} sensor stated by {by}")


def apply_size_flags(path: Path, rec: Recording, width: int | None, height: int | None) -> None:
    """An evpose HDF5 file states its size in its calibration or metadata; flags may only agree, or fill it in."""
    by = "its calibration" if rec.calibration is not None else "its metadata"
    check_size_flags(path, rec.sensor_size, width, height, by)
    if width is not None and height is not None and rec.sensor_size is None:
        rec.metadata["width"], rec.metadata["height"] = int(width), int(height)


def _open_stream(path: str | Path, width: int | None = None, height: int | None = None, **options) -> RecordingStream:
    path = Path(path)
    if (width is None) != (height is None):
        raise ConfigError("give both width and height of the sensor, or neither")
    if width is not None and (width <= 0 or height <= 0 or width > 65536 or height > 65536):
        raise ConfigError(f"sensor size must be 1..65536 pixels, got {width}x{height}")
    fmt = detect_format(path)
    if fmt is SourceFormat.ECD:
        from evpose.io import ecd

        ctx, size = ecd.read_ecd_context(path, width, height)
        w, h = size if size else (None, None)
        events = path / ecd.EVENTS_FILE
        return RecordingStream(ctx, fmt, lambda cb=None: ecd.iter_ecd_events(events, w, h, on_bytes=cb), events.stat().st_size, "B")
    if fmt is SourceFormat.EVPOSE_H5:
        from evpose.io.h5 import H5RecordingReader

        with H5RecordingReader(path) as r:
            ctx = Recording(EventArray.empty(), r.imu, r.ground_truth, r.calibration, dict(r.metadata), source=path)
            n = r.n_events
        apply_size_flags(path, ctx, width, height)

        size = ctx.sensor_size

        def batches(cb=None):
            offset, last = 0, None
            with H5RecordingReader(path) as reader:
                for b in reader.iter_chunks():
                    check_events(b, offset, last, size, path)
                    offset, last = offset + len(b), (int(b.t[-1]) if len(b) else last)
                    if cb:
                        cb(len(b))
                    yield b

        return RecordingStream(ctx, fmt, batches, n, "ev")
    if fmt is SourceFormat.EVENT_H5:
        from evpose.io import event_h5

        return event_h5.open_event_h5_stream(path, width, height)
    from evpose.io import rosbag

    return rosbag.open_bag_stream(path, width=width, height=height, **options)


def open_recording(path: str | Path, width: int | None = None, height: int | None = None, **options) -> Recording:
    """Read any supported recording fully into memory (see :func:`detect_format`), checked: unsorted timestamps,
    pixels outside the sensor, polarities other than +1/-1 and NaNs in the IMU or ground truth raise
    :class:`InputError` naming the file and the first bad record, whatever command reads it."""
    path = Path(path)
    if detect_format(path) is SourceFormat.EVPOSE_H5:
        from evpose.io.h5 import read_recording_h5

        if (width is None) != (height is None):
            raise ConfigError("give both width and height of the sensor, or neither")
        rec = read_recording_h5(path)
        apply_size_flags(path, rec, width, height)
    else:
        stream = open_stream(path, width, height, **options)
        rec = stream.context
        rec.events = EventArray.concatenate(list(stream.batches(None)))
    rec.validate()
    check_nonnegative_times(rec.events, path)
    check_span(rec.events.t, path)  # what `convert` refuses (the HDF5 index's span), every reader refuses
    return rec


def require_calibration(rec: Recording, needs: str) -> None:
    """Refuse a recording without a camera calibration for a command that ``needs`` one (e.g. "tracking needs
    intrinsics"), saying what would give it one: an ECD ``calib.txt`` without a sensor size was the same bare "no
    camera calibration" as a folder without any, though ``--width/--height`` was all it lacked."""
    if rec.calibration is not None:
        return
    hint = " (its calib.txt has intrinsics but no sensor size: pass --width/--height)" if "ecd_calib_txt" in rec.metadata else ""
    raise InputError(rec.source, f"the recording has no camera calibration{hint}; {needs}")
