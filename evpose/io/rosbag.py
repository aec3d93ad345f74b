"""ROS1 and ROS2 bags via ``rosbags``: ``dvs_msgs/EventArray``, ``sensor_msgs/Imu``, ``geometry_msgs/PoseStamped``, ``sensor_msgs/CameraInfo``.

EventArray payloads are never turned into one Python object per event
(rosbags' deserialiser runs at ~0.1-1 Mev/s). The raw bytes are viewed as a
``uint8`` numpy array (no copy) and a numba kernel reads the packed fields in
one pass straight into the event columns. Reading a packed structured view
field by field was tried first and was several times slower (0.30 s vs 0.06 s
for 2 M events in the same profiled run; unaligned field copies
plus int64 conversions dominated). Layouts:

* ROS1: after the header, ``u4 height, u4 width, u4 n`` then ``n`` packed
  13-byte events ``u2 x, u2 y, u4 sec, u4 nsec, u1 polarity``.
* ROS2 (CDR, little endian): the same fields, but CDR aligns each primitive
  to its size from the payload start, so event 0 occupies 14 bytes
  (``x@0 y@2 sec@4 nsec@8 p@12``) and every later event 16 bytes
  (``x@0 y@2 sec@6 nsec@10 p@14``); the last event has no trailing pad.

:func:`write_rosbag` produces such bags the same way (used by tests and benchmarks).
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterator

import numba as nb
import numpy as np

from evpose.core.camera import CameraCalibration, DistortionModel
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory
from evpose.errors import InputError
from evpose.io.atomic import atomic_path

EVENT_ARRAY = "dvs_msgs/msg/EventArray"
IMU = "sensor_msgs/msg/Imu"
POSE = "geometry_msgs/msg/PoseStamped"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"

_EVENT_MSG = "uint16 x\nuint16 y\nbuiltin_interfaces/Time ts\nbool polarity\n"
_EVENT_ARRAY_MSG = "std_msgs/Header header\nuint32 height\nuint32 width\ndvs_msgs/Event[] events\n"

ROS1_EVENT = np.dtype([("x", "<u2"), ("y", "<u2"), ("sec", "<u4"), ("nsec", "<u4"), ("p", "u1")])
"""Packed 13-byte ROS1 event record (used by the encoder)."""
CDR_EVENT_FIRST = np.dtype({"names": ["x", "y", "sec", "nsec", "p"], "formats": ["<u2", "<u2", "<i4", "<u4", "u1"], "offsets": [0, 2, 4, 8, 12], "itemsize": 14})
CDR_EVENT_REST = np.dtype({"names": ["x", "y", "sec", "nsec", "p"], "formats": ["<u2", "<u2", "<i4", "<u4", "u1"], "offsets": [0, 2, 6, 10, 14], "itemsize": 16})
_BATCH_EVENTS = 1 << 20


class BagError(InputError):
    """A bag that cannot be read as an event recording."""


def make_typestore(ros1: bool = False):
    """ROS2 Humble (or ROS1 Noetic, whose Header has ``seq``) types plus ``dvs_msgs/msg/{Event,EventArray}``."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    types = {}
    types.update(get_types_from_msg(_EVENT_MSG, "dvs_msgs/msg/Event"))
    types.update(get_types_from_msg(_EVENT_ARRAY_MSG, EVENT_ARRAY))
    store.register(types)
    return store


# ------------------------------------------------------------------ decoding
def _align(o: int, n: int) -> int:
    return (o + n - 1) // n * n


@nb.njit(cache=True, nogil=True)
def _unpack_events(buf, o, n, first_size, stride, off0, off1, signed_sec, out_t, out_x, out_y, out_p, pos):
    """Decode ``n`` little-endian events starting at ``buf[o]`` into the outputs at ``pos``.

    Event 0 uses field offsets ``off0`` and occupies ``first_size`` bytes; later
    events use ``off1`` with a ``stride`` (ROS1: 13/13, same offsets; CDR: 14/16).
    One pass, no intermediate record arrays.
    """
    for k in range(n):
        if k == 0:
            s = o
            ox, oy, osec, onsec, op = off0
        else:
            s = o + first_size + (k - 1) * stride
            ox, oy, osec, onsec, op = off1
        x = np.int64(buf[s + ox]) | (np.int64(buf[s + ox + 1]) << 8)
        y = np.int64(buf[s + oy]) | (np.int64(buf[s + oy + 1]) << 8)
        q = s + osec
        sec = np.int64(buf[q]) | (np.int64(buf[q + 1]) << 8) | (np.int64(buf[q + 2]) << 16) | (np.int64(buf[q + 3]) << 24)
        if signed_sec and sec >= 2147483648:
            sec -= 4294967296
        q = s + onsec
        nsec = np.int64(buf[q]) | (np.int64(buf[q + 1]) << 8) | (np.int64(buf[q + 2]) << 16) | (np.int64(buf[q + 3]) << 24)
        out_t[pos + k] = sec * 1000000 + (nsec + 500) // 1000
        out_x[pos + k] = x
        out_y[pos + k] = y
        out_p[pos + k] = 1 if buf[s + op] != 0 else -1
    return pos + n


def _event_block(raw: bytes, is2: bool) -> tuple[int, int, int, int]:
    """(offset of event 0 in ``raw``, event count, width, height); raises ValueError if the payload is too short."""
    mv = memoryview(raw)
    if is2:
        if len(raw) < 4 or raw[1] != 1:
            raise ValueError("not little-endian CDR")
        flen = int(np.frombuffer(mv, "<u4", 1, 12)[0])
        o = 4 + _align(12 + flen, 4)
        height, width, n = (int(v) for v in np.frombuffer(mv, "<u4", 3, o))
        o += 12
        need = 0 if n == 0 else 13 if n == 1 else 14 + 16 * (n - 2) + 15
    else:
        flen = int(np.frombuffer(mv, "<u4", 1, 12)[0])
        o = 16 + flen
        height, width, n = (int(v) for v in np.frombuffer(mv, "<u4", 3, o))
        o += 12
        need = 13 * n
    if o + need > len(raw):
        raise ValueError(f"payload holds {len(raw) - o} bytes of events, {n} events need {need}")
    return o, n, width, height


_ROS1_LAYOUT = (13, 13, (0, 2, 4, 8, 12), (0, 2, 4, 8, 12), False)
_CDR_LAYOUT = (14, 16, (0, 2, 4, 8, 12), (0, 2, 6, 10, 14), True)


def decode_event_array(raw: bytes, ros2: bool) -> tuple[EventArray, int, int]:
    """(events, width, height) of one serialised EventArray (ROS1 or CDR); ValueError if malformed."""
    o, n, width, height = _event_block(raw, ros2)
    first_size, stride, off0, off1, signed = _CDR_LAYOUT if ros2 else _ROS1_LAYOUT
    cols = _alloc(n)
    _unpack_events(np.frombuffer(raw, np.uint8), o, n, first_size, stride, off0, off1, signed, *cols, 0)
    return EventArray(*cols), width, height


def _stamp_us(stamp) -> int:
    sec = stamp.sec
    nsec = stamp.nanosec
    return int(sec) * 1_000_000 + (int(nsec) + 500) // 1000


# ------------------------------------------------------------------ reading
def _bag_paths(path: Path) -> list[Path]:
    if path.is_file() and path.suffix.lower() in (".db3", ".mcap"):
        if not (path.parent / "metadata.yaml").is_file():
            raise BagError(path, "ROS2 bag file without metadata.yaml next to it; give the bag folder")
        return [path.parent]
    return [path]


def _pick(conns, msgtype: str, topic: str | None, path: Path, kind: str, required: bool):
    topics = sorted({f"{c.topic} ({c.msgtype})" for c in conns})
    if topic is not None:
        hits = [c for c in conns if c.topic == topic]
        if not hits:
            raise BagError(path, f"unknown {kind} topic {topic!r}; the bag has: {', '.join(topics) or 'no topics'}")
        if hits[0].msgtype != msgtype:
            raise BagError(path, f"topic {topic!r} carries {hits[0].msgtype}, not {msgtype}")
        return hits
    hits = [c for c in conns if c.msgtype == msgtype]
    if not hits:
        if required:
            raise BagError(path, f"no {msgtype} topic; the bag has: {', '.join(topics) or 'no topics'}")
        return []
    first = sorted({c.topic for c in hits})[0]  # deterministic choice when a bag has several
    return [c for c in hits if c.topic == first]


def _calibration_from_info(msg, size) -> CameraCalibration | None:
    k = np.asarray(getattr(msg, "k", getattr(msg, "K", None)), dtype=np.float64).reshape(-1)
    d = [float(v) for v in np.asarray(getattr(msg, "d", getattr(msg, "D", [])), dtype=np.float64).reshape(-1)]
    w, h = int(msg.width), int(msg.height)
    if (w == 0 or h == 0) and size:
        w, h = size
    model_name = str(msg.distortion_model).lower()
    if k.size != 9 or k[0] <= 0 or w <= 0 or h <= 0:
        return None
    if model_name in ("plumb_bob", "radtan") and any(d):
        model, dist = DistortionModel.RADTAN, tuple((d + [0.0] * 5)[:5])
    elif model_name in ("equidistant", "fisheye", "kannala_brandt") and len(d) >= 4:
        model, dist = DistortionModel.EQUIDISTANT, tuple(d[:4])
    elif not any(d):
        model, dist = DistortionModel.NONE, ()
    else:
        return None
    return CameraCalibration(w, h, float(k[0]), float(k[4]), float(k[2]), float(k[5]), model, dist)


def open_bag_stream(path: str | Path, events_topic: str | None = None, imu_topic: str | None = None, pose_topic: str | None = None,
                    width: int | None = None, height: int | None = None):
    """A :class:`~evpose.io.open.RecordingStream` over a ROS1 ``.bag`` or ROS2 bag (folder, ``.db3``, ``.mcap``).
    ``width``/``height`` give the sensor size when the bag states none (EventArray size 0x0, no camera_info)."""
    from rosbags.highlevel import AnyReader, AnyReaderError

    from evpose.io.open import RecordingStream, SourceFormat, check_size_flags

    path = Path(path)
    paths = _bag_paths(path)
    store = make_typestore()
    try:
        reader = AnyReader(paths, default_typestore=store)
        reader.open()
    except (AnyReaderError, FileNotFoundError, OSError) as exc:
        # rosbags quotes whole YAML parser reports: keep their first line, the message must stay one line.
        raise BagError(path, f"cannot open bag ({' '.join(str(exc).split(chr(10))[0].split())})") from None
    except UnicodeDecodeError:
        # rosbags decodes the ROS1 magic line as text: random bytes end here, not in AnyReaderError.
        raise BagError(path, "cannot open bag (not a ROS1 bag: no '#ROSBAG V2.0' header)") from None
    except Exception as exc:  # noqa: BLE001
        # A damaged index record fails rosbags' own sanity checks: a bare AssertionError traceback ("assert size == 47"
        # in read_index_data) for 4 KiB of zeros near a ROS1 bag's end (session 30's fuzzing).
        detail = " ".join(str(exc).split())
        raise BagError(path, f"cannot open bag, it is damaged ({type(exc).__name__}{': ' + detail if detail else ''})") from None
    try:
        conns = reader.connections
        ev_conns = _pick(conns, EVENT_ARRAY, events_topic, path, "events", True)
        imu_conns = _pick(conns, IMU, imu_topic, path, "IMU", False)
        pose_conns = _pick(conns, POSE, pose_topic, path, "pose", False)
        info_conns = _pick(conns, CAMERA_INFO, None, path, "camera info", False)
        ev_topic = ev_conns[0].topic
        n_msgs = sum(c.msgcount for c in ev_conns)
        if n_msgs == 0:
            raise BagError(path, f"topic {ev_topic!r} has no messages (no events)")
        imu = None
        if imu_conns:
            rows = []
            for i, (c, _, raw) in enumerate(_messages(reader, imu_conns, path)):
                try:
                    m = reader.deserialize(raw, c.msgtype)
                except Exception as exc:  # rosbags raises assorted errors on corrupt payloads
                    raise BagError(path, f"cannot decode ({exc})", f"{c.topic} message {i}") from None
                a, g = m.linear_acceleration, m.angular_velocity
                rows.append((_stamp_us(m.header.stamp), a.x, a.y, a.z, g.x, g.y, g.z))
            arr = np.asarray(rows, dtype=np.float64).reshape(-1, 7)
            imu = ImuSamples.from_arrays(np.array([r[0] for r in rows], np.int64), arr[:, 1:4], arr[:, 4:7])
            imu.validate(source=f"{path} {imu_conns[0].topic}")
        gt = None
        if pose_conns:
            ts, pos, quat = [], [], []
            for i, (c, _, raw) in enumerate(_messages(reader, pose_conns, path)):
                try:
                    m = reader.deserialize(raw, c.msgtype)
                except Exception as exc:
                    raise BagError(path, f"cannot decode ({exc})", f"{c.topic} message {i}") from None
                p, q = m.pose.position, m.pose.orientation
                ts.append(_stamp_us(m.header.stamp))
                pos.append((p.x, p.y, p.z))
                quat.append((q.x, q.y, q.z, q.w))
            gt = Trajectory.from_arrays(np.array(ts, np.int64), np.array(pos), np.array(quat))
            gt.validate(source=f"{path} {pose_conns[0].topic}")
        # The sensor size is stated by the first EventArray message.
        size = None
        for k, (c, _, raw) in enumerate(_messages(reader, ev_conns, path)):
            try:
                _, _, w, h = _event_block(raw, reader.is2)
            except (ValueError, IndexError, TypeError) as exc:
                raise BagError(path, f"malformed EventArray ({exc})", f"{c.topic} message {k}") from None
            if w > 0 and h > 0:
                size = (w, h)
            break
        check_size_flags(path, size, width, height, f"its EventArray messages ({ev_conns[0].topic})")
        if size is None and width is not None and height is not None:
            size = (int(width), int(height))
        calibration = None
        if info_conns:
            for c, _, raw in _messages(reader, info_conns, path):
                # A corrupt payload was an AnyReaderError traceback; CameraCalibration's own checks named no file.
                try:
                    calibration = _calibration_from_info(reader.deserialize(raw, c.msgtype), size)
                except InputError as exc:
                    raise BagError(path, exc.problem, f"{c.topic} message 0") from None
                except Exception as exc:  # rosbags raises assorted errors on corrupt payloads
                    raise BagError(path, f"cannot decode ({exc})", f"{c.topic} message 0") from None
                break
    finally:
        reader.close()
    metadata = {"source_format": "ros2-bag" if reader.is2 else "ros1-bag", "events_topic": ev_topic}
    if imu_conns:
        metadata["imu_topic"] = imu_conns[0].topic
    if pose_conns:
        metadata["pose_topic"] = pose_conns[0].topic
    if calibration is not None:
        check_size_flags(path, (calibration.width, calibration.height), width, height, f"its camera_info ({info_conns[0].topic})")
    if size is not None and calibration is None:
        metadata["width"], metadata["height"] = size
    ctx = Recording(EventArray.empty(), imu, gt, calibration, metadata, source=path)

    def batches(on_progress=None) -> Iterator[EventArray]:
        yield from _iter_events(paths, path, ev_topic, size, store, on_progress)

    fmt = SourceFormat.ROS2_BAG if reader.is2 else SourceFormat.ROS1_BAG
    return RecordingStream(ctx, fmt, batches, n_msgs, "msg")


def _messages(reader, conns, path: Path):
    """``reader.messages(connections=conns)``, a damaged bag raised while reading it as our :class:`BagError` naming the
    topic and the message: rosbags checks the chunks it reads only as it reads them, so a bag whose index opened
    cleanly ended in its ReaderError traceback ("Header could not be read from file", "Could not read uint8 field
    'op'") on 4 KiB of garbage 80 % into the file (session 30's fuzzing, /tmp/s30/fuzz30/)."""
    it = reader.messages(connections=conns)
    topic = conns[0].topic if conns else "?"
    k = 0
    while True:
        try:
            item = next(it)
        except StopIteration:
            return
        except Exception as exc:  # noqa: BLE001 - rosbags raises ReaderError, struct.error, decompression errors...
            detail = " ".join(str(exc).split()) or type(exc).__name__
            raise BagError(path, f"cannot read the bag, it is damaged ({detail})", f"{topic} message {k}") from None
        yield item
        k += 1


def _iter_events(paths, path, topic, size, store, on_progress) -> Iterator[EventArray]:
    from rosbags.highlevel import AnyReader

    cap = 2 * _BATCH_EVENTS
    cols = _alloc(cap)
    pos = 0
    starts: list[int] = []  # batch position of each message's first event
    msg_ids: list[int] = []
    last_t: int | None = None
    k = 0

    def flush(n):
        nonlocal last_t
        ev = EventArray(*(c[:n].copy() for c in cols))
        try:
            ev.validate(*(size if size else (None, None)), source=str(path))
            if last_t is not None and n and int(ev.t[0]) < last_t:
                raise InputError(path, f"timestamp {int(ev.t[0])} us is earlier than the previous {last_t} us (timestamps must be sorted)", "event 0")
        except InputError as exc:
            # Map the batch index back to the message it came from.
            i = int(exc.record.split()[-1])
            j = int(np.searchsorted(np.asarray(starts), i, side="right")) - 1
            raise BagError(path, exc.problem, f"{topic} message {msg_ids[j]}, event {i - starts[j]}") from None
        if n:
            last_t = int(ev.t[-1])
        return ev

    with AnyReader(paths, default_typestore=store) as reader:
        first_size, stride, off0, off1, signed = _CDR_LAYOUT if reader.is2 else _ROS1_LAYOUT
        conns = [c for c in reader.connections if c.topic == topic]
        for c, _, raw in _messages(reader, conns, path):
            try:
                o, n, _, _ = _event_block(raw, reader.is2)
            except (ValueError, IndexError, TypeError) as exc:
                raise BagError(path, f"malformed EventArray ({exc})", f"{topic} message {k}") from None
            if pos + n > cap:
                if pos:
                    yield flush(pos)
                    pos, starts, msg_ids = 0, [], []
                if n > cap:
                    cap = n
                    cols = _alloc(cap)
            if n:
                starts.append(pos)
                msg_ids.append(k)
                pos = _unpack_events(np.frombuffer(raw, np.uint8), o, n, first_size, stride, off0, off1, signed, *cols, pos)
            k += 1
            if on_progress is not None:
                on_progress(1)
            if pos >= _BATCH_EVENTS:
                yield flush(pos)
                pos, starts, msg_ids = 0, [], []
    if pos:
        yield flush(pos)


def _alloc(n: int):
    return np.empty(n, np.int64), np.empty(n, np.uint16), np.empty(n, np.uint16), np.empty(n, np.int8)


# ------------------------------------------------------------------ writing
def encode_event_array_ros1(ev: EventArray, width: int, height: int, seq: int = 0, frame_id: str = "") -> bytes:
    stamp = int(ev.t[0]) if len(ev) else 0
    rec = np.empty(len(ev), ROS1_EVENT)
    rec["x"], rec["y"], rec["p"] = ev.x, ev.y, (ev.p > 0)
    rec["sec"], rec["nsec"] = ev.t // 1_000_000, (ev.t % 1_000_000) * 1000
    fid = frame_id.encode()
    head = np.array([seq, stamp // 1_000_000, (stamp % 1_000_000) * 1000, len(fid)], "<u4").tobytes() + fid
    return head + np.array([height, width, len(ev)], "<u4").tobytes() + rec.tobytes()


def encode_event_array_cdr(ev: EventArray, width: int, height: int, frame_id: str = "") -> bytes:
    stamp = int(ev.t[0]) if len(ev) else 0
    fid = frame_id.encode() + b"\x00"
    body = np.array([stamp // 1_000_000], "<i4").tobytes() + np.array([(stamp % 1_000_000) * 1000, len(fid)], "<u4").tobytes() + fid
    body += b"\x00" * (_align(len(body), 4) - len(body))
    body += np.array([height, width, len(ev)], "<u4").tobytes()
    n = len(ev)
    if n:
        rec = np.zeros(n, CDR_EVENT_REST)
        rec["x"], rec["y"], rec["p"] = ev.x, ev.y, (ev.p > 0)
        rec["sec"], rec["nsec"] = ev.t // 1_000_000, (ev.t % 1_000_000) * 1000
        first = np.zeros(1, CDR_EVENT_FIRST)
        for name in ("x", "y", "sec", "nsec", "p"):
            first[name] = rec[name][0]
        body += first.tobytes() + rec[1:].tobytes()
        body = body[:-1]  # no pad byte after the last event
    return b"\x00\x01\x00\x00" + body


def write_rosbag(
    path: str | Path,
    recording: Recording,
    ros2: bool = False,
    events_per_message: int = 5000,
    events_topic: str = "/dvs/events",
    imu_topic: str = "/dvs/imu",
    pose_topic: str = "/optitrack/pose",
) -> None:
    """Write ``recording`` as a ROS1 ``.bag`` or a ROS2 bag folder (sqlite3), atomically."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import Writer as Writer2

    store = make_typestore(ros1=not ros2)
    size = recording.sensor_size
    if size is None:
        raise InputError(path, "writing a bag needs the sensor size (calibration or metadata width/height)")
    w, h = size
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    Vec = store.types["geometry_msgs/msg/Vector3"]
    Quat = store.types["geometry_msgs/msg/Quaternion"]

    def stamp(t_us: int):
        return Time(sec=int(t_us // 1_000_000), nanosec=int(t_us % 1_000_000) * 1000)

    def header(t_us: int, frame: str):
        extra = {} if ros2 else {"seq": 0}
        return Header(stamp=stamp(t_us), frame_id=frame, **extra)

    inputs = (recording.source,) if recording.source is not None else ()
    # same_name: rosbags names a ROS2 bag's storage file (and records it in metadata.yaml and the database) after the
    # folder: a temporary folder's name made it a hidden ".NAME.x1y2z3.tmp.db3", different on every run.
    with atomic_path(path, inputs=inputs, is_dir=ros2, same_name=True) as tmp:
        ser = store.serialize_cdr if ros2 else store.serialize_ros1
        writer = Writer2(tmp, version=9) if ros2 else Writer1(tmp)
        with writer:
            kw = {"typestore": store}
            c_ev = writer.add_connection(events_topic, EVENT_ARRAY, **kw)
            ev = recording.events
            for k, i0 in enumerate(range(0, len(ev), events_per_message)):
                part = ev[i0 : i0 + events_per_message]
                raw = encode_event_array_cdr(part, w, h) if ros2 else encode_event_array_ros1(part, w, h, seq=k)
                writer.write(c_ev, int(part.t[-1]) * 1000, raw)
            if recording.imu is not None:
                c = writer.add_connection(imu_topic, IMU, **kw)
                Imu = store.types[IMU]
                for t, a, g in zip(recording.imu.t.tolist(), recording.imu.acc.tolist(), recording.imu.gyro.tolist()):
                    msg = Imu(header=header(t, "imu"), orientation=Quat(x=0.0, y=0.0, z=0.0, w=1.0), orientation_covariance=np.zeros(9), angular_velocity=Vec(x=g[0], y=g[1], z=g[2]), angular_velocity_covariance=np.zeros(9), linear_acceleration=Vec(x=a[0], y=a[1], z=a[2]), linear_acceleration_covariance=np.zeros(9))
                    writer.write(c, t * 1000, ser(msg, IMU))
            if recording.ground_truth is not None:
                c = writer.add_connection(pose_topic, POSE, **kw)
                PoseStamped, Pose, Point = store.types[POSE], store.types["geometry_msgs/msg/Pose"], store.types["geometry_msgs/msg/Point"]
                gt = recording.ground_truth
                for t, p, q in zip(gt.t.tolist(), gt.position.tolist(), gt.quat_xyzw.tolist()):
                    msg = PoseStamped(header=header(t, "world"), pose=Pose(position=Point(x=p[0], y=p[1], z=p[2]), orientation=Quat(x=q[0], y=q[1], z=q[2], w=q[3])))
                    writer.write(c, t * 1000, ser(msg, POSE))
            cal = recording.calibration
            if cal is not None:
                c = writer.add_connection("/dvs/camera_info", CAMERA_INFO, **kw)
                Info = store.types[CAMERA_INFO]
                RoI = store.types["sensor_msgs/msg/RegionOfInterest"]
                dmodel = {DistortionModel.RADTAN: "plumb_bob", DistortionModel.EQUIDISTANT: "equidistant", DistortionModel.NONE: "plumb_bob"}[cal.model]
                K = np.array([cal.fx, 0, cal.cx, 0, cal.fy, cal.cy, 0, 0, 1], np.float64)
                P = np.array([cal.fx, 0, cal.cx, 0, 0, cal.fy, cal.cy, 0, 0, 0, 1, 0], np.float64)
                t0 = recording.t_start_us
                mats = {"d": np.array(cal.dist if cal.dist else [0.0] * 5, np.float64), "k": K, "r": np.eye(3).reshape(-1), "p": P}
                if not ros2:
                    mats = {key.upper(): v for key, v in mats.items()}  # ROS1 names these D K R P
                msg = Info(header=header(t0, "cam"), height=cal.height, width=cal.width, distortion_model=dmodel, binning_x=0, binning_y=0, roi=RoI(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False), **mats)
                writer.write(c, t0 * 1000, ser(msg, CAMERA_INFO))
