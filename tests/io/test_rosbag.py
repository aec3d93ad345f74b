"""ROS1/ROS2 bags: the packed-bytes EventArray codec matches rosbags, bags round trip, bad bags are named."""

import numpy as np
import pytest

from io_factory import assert_same_recording, make_recording
from evpose.core.events import EventArray
from evpose.errors import InputError
from evpose.io.open import open_recording, open_stream
from evpose.io.rosbag import (
    EVENT_ARRAY,
    decode_event_array,
    encode_event_array_cdr,
    encode_event_array_ros1,
    make_typestore,
    write_rosbag,
)


@pytest.mark.parametrize("n", [0, 1, 2, 7])
@pytest.mark.parametrize("ros2", [False, True])
def test_event_array_bytes_equal_rosbags_serialisation(n, ros2):
    rng = np.random.default_rng(n)
    ev = EventArray.from_arrays(np.sort(rng.integers(0, 10**13, n)), rng.integers(0, 640, n), rng.integers(0, 480, n), rng.integers(0, 2, n))
    store = make_typestore(ros1=not ros2)
    Msg, Event = store.types[EVENT_ARRAY], store.types["dvs_msgs/msg/Event"]
    Header, Time = store.types["std_msgs/msg/Header"], store.types["builtin_interfaces/msg/Time"]
    t0 = int(ev.t[0]) if n else 0
    events = [Event(x=int(x), y=int(y), ts=Time(sec=int(t // 10**6), nanosec=int(t % 10**6) * 1000), polarity=bool(p > 0)) for t, x, y, p in zip(ev.t, ev.x, ev.y, ev.p)]
    hdr = Header(stamp=Time(sec=t0 // 10**6, nanosec=(t0 % 10**6) * 1000), frame_id="", **({} if ros2 else {"seq": 3}))
    msg = Msg(header=hdr, height=480, width=640, events=events)
    ref = bytes(store.serialize_cdr(msg, EVENT_ARRAY) if ros2 else store.serialize_ros1(msg, EVENT_ARRAY))
    ours = encode_event_array_cdr(ev, 640, 480) if ros2 else encode_event_array_ros1(ev, 640, 480, seq=3)
    assert ours == ref
    got, w, h = decode_event_array(ref, ros2)
    assert (w, h, len(got)) == (640, 480, n)
    for c in "txyp":
        np.testing.assert_array_equal(getattr(got, c), getattr(ev, c))


@pytest.mark.parametrize("ros2", [False, True])
def test_bag_round_trip_keeps_events_imu_ground_truth_and_calibration(tmp_path, ros2):
    rec = make_recording(n=3000, duration_us=500_000)
    path = tmp_path / ("b" if ros2 else "b.bag")
    write_rosbag(path, rec, ros2=ros2, events_per_message=700)
    back = open_recording(path)
    assert back.metadata["source_format"] == ("ros2-bag" if ros2 else "ros1-bag")
    assert back.metadata["events_topic"] == "/dvs/events"
    assert_same_recording(rec, back, metadata=False, extrinsic=False)


def test_ros2_db3_file_is_opened_through_its_folder(tmp_path):
    rec = make_recording(n=100, duration_us=10_000)
    write_rosbag(tmp_path / "b", rec, ros2=True)
    db3 = next((tmp_path / "b").glob("*.db3"))
    assert len(open_recording(db3).events) == 100


def test_unknown_topic_lists_what_the_bag_has(tmp_path):
    rec = make_recording(n=100, duration_us=10_000)
    write_rosbag(tmp_path / "b.bag", rec)
    with pytest.raises(InputError, match=r"b.bag: unknown events topic '/cam/events'; the bag has: .*/dvs/events \(dvs_msgs/msg/EventArray\)"):
        open_stream(tmp_path / "b.bag", events_topic="/cam/events")
    with pytest.raises(InputError, match="carries sensor_msgs/msg/Imu, not dvs_msgs/msg/EventArray"):
        open_stream(tmp_path / "b.bag", events_topic="/dvs/imu")


def test_bag_without_events_is_an_input_error(tmp_path):
    rec = make_recording(n=0)
    write_rosbag(tmp_path / "b.bag", rec)
    with pytest.raises(InputError, match="topic '/dvs/events' has no messages"):
        open_recording(tmp_path / "b.bag")


def test_unsorted_events_name_the_message_and_event(tmp_path):
    rec = make_recording(n=1000, duration_us=100_000)
    t = rec.events.t.copy()
    t[730] = t[0] - 1
    rec.events = EventArray(t, rec.events.x, rec.events.y, rec.events.p)
    write_rosbag(tmp_path / "b.bag", rec, events_per_message=100)
    with pytest.raises(InputError, match=r"/dvs/events message 7, event 30: timestamp .* earlier"):
        open_recording(tmp_path / "b.bag")


def test_pixels_outside_the_stated_sensor_are_named(tmp_path):
    rec = make_recording(n=500, duration_us=100_000, width=64, height=48)
    rec.calibration = None
    rec.metadata = {"width": 32, "height": 48}
    write_rosbag(tmp_path / "b.bag", rec, events_per_message=100)
    with pytest.raises(InputError, match=r"/dvs/events message \d+, event \d+: x=\d+ is outside the sensor width 32"):
        open_recording(tmp_path / "b.bag")


def test_bag_without_event_topic_lists_its_topics(tmp_path):
    from rosbags.rosbag1 import Writer

    store = make_typestore(ros1=True)
    with Writer(tmp_path / "imu.bag") as w:
        w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
    with pytest.raises(InputError, match=r"no dvs_msgs/msg/EventArray topic; the bag has: /imu \(sensor_msgs/msg/Imu\)"):
        open_recording(tmp_path / "imu.bag")


def test_truncated_event_message_is_named(tmp_path):
    from rosbags.rosbag1 import Writer

    store = make_typestore(ros1=True)
    ev = EventArray.from_arrays([1, 2, 3], [0, 1, 2], [0, 1, 2], [0, 1, 1])
    with Writer(tmp_path / "t.bag") as w:
        c = w.add_connection("/dvs/events", EVENT_ARRAY, typestore=store)
        w.write(c, 1000, encode_event_array_ros1(ev[:2], 8, 8))
        w.write(c, 2000, encode_event_array_ros1(ev, 8, 8)[:-5])
    with pytest.raises(InputError, match=r"t.bag: /dvs/events message 1: malformed EventArray"):
        open_recording(tmp_path / "t.bag")


def test_corrupt_bag_is_an_input_error(tmp_path):
    (tmp_path / "x.bag").write_bytes(b"not a bag at all")
    with pytest.raises(InputError, match="x.bag: cannot open bag"):
        open_recording(tmp_path / "x.bag")


def test_random_bytes_named_bag_is_a_one_line_error_not_a_unicode_traceback(tmp_path):
    path = tmp_path / "junk.bag"
    path.write_bytes(b"\x8e\xae\xff" + bytes(range(256)) * 4)  # not UTF-8 in the first line
    with pytest.raises(InputError, match="not a ROS1 bag") as info:
        open_recording(path)
    assert "\n" not in str(info.value)


def test_ros2_metadata_yaml_error_is_reported_in_one_line(tmp_path):
    d = tmp_path / "bag"
    d.mkdir()
    (d / "metadata.yaml").write_text("garbage: [\n")
    with pytest.raises(InputError, match="cannot open bag") as info:
        open_recording(d)
    assert "\n" not in str(info.value)


def test_ros2_bag_is_the_same_bytes_on_every_write_with_its_storage_file_named_after_the_bag(tmp_path):
    # The storage file was named after the temporary folder (".b.x1y2z3.tmp.db3"): hidden, and new on every run.
    rec = make_recording(n=300, duration_us=20_000)
    write_rosbag(tmp_path / "one" / "b", rec, ros2=True)
    write_rosbag(tmp_path / "two" / "b", rec, ros2=True)
    files = sorted(p.name for p in (tmp_path / "one" / "b").iterdir())
    assert files == ["b.db3", "metadata.yaml"]
    for name in files:
        assert (tmp_path / "one" / "b" / name).read_bytes() == (tmp_path / "two" / "b" / name).read_bytes()
    assert len(open_recording(tmp_path / "two" / "b").events) == 300


def _bag_with_camera_info(path, info_bytes):
    from rosbags.rosbag1 import Writer

    store = make_typestore(ros1=True)
    ev = EventArray.from_arrays([1, 2, 3], [0, 1, 2], [0, 1, 2], [0, 1, 1])
    with Writer(path) as w:
        c = w.add_connection("/dvs/events", EVENT_ARRAY, typestore=store)
        w.write(c, 1000, encode_event_array_ros1(ev, 8, 8))
        ci = w.add_connection("/dvs/camera_info", "sensor_msgs/msg/CameraInfo", typestore=store)
        w.write(ci, 1000, info_bytes(store))


def _camera_info(store, fx):
    T = store.types
    header = T["std_msgs/msg/Header"](seq=0, stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id="")
    roi = T["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    msg = T["sensor_msgs/msg/CameraInfo"](header=header, height=8, width=8, distortion_model="plumb_bob", D=np.zeros(5),
                                          K=np.array([fx, 0, 4, 0, 5.0, 4, 0, 0, 1]), R=np.eye(3).ravel(), P=np.zeros(12),
                                          binning_x=0, binning_y=0, roi=roi)
    return store.serialize_ros1(msg, "sensor_msgs/msg/CameraInfo")


@pytest.mark.parametrize("payload, message", [
    # A corrupt payload was rosbags' AnyReaderError traceback.
    (lambda store: b"\xff" * 20, r"c.bag: /dvs/camera_info message 0: cannot decode"),
    # CameraCalibration's own check named no file: "error: calibration has NaN or infinite values".
    (lambda store: _camera_info(store, float("nan")), r"c.bag: /dvs/camera_info message 0: calibration has NaN or infinite values"),
])
def test_a_bad_camera_info_names_the_bag_and_message(tmp_path, payload, message):
    _bag_with_camera_info(tmp_path / "c.bag", payload)
    with pytest.raises(InputError, match=message):
        open_recording(tmp_path / "c.bag")
