"""A bag damaged inside its chunks, index or database is one InputError naming the bag (and the topic and message
where the damage was met), never the bag library's own exception: rosbags checks what it reads only as it reads it."""

import numpy as np
import pytest

from io_factory import make_recording
from evpose.errors import InputError
from evpose.io.open import open_recording
from evpose.io.rosbag import write_rosbag


def _damaged_reads(tmp_path, ros2: bool) -> list[str]:
    """Overwrite 4 KiB with zeros at 12 places over the bag's storage file; the message of each read that fails."""
    rec = make_recording(n=3000, duration_us=500_000)
    src = tmp_path / ("b" if ros2 else "b.bag")
    write_rosbag(src, rec, ros2=ros2, events_per_message=700)
    storage = next(src.glob("*.db3")) if ros2 else src
    data = storage.read_bytes()
    messages = []
    for at in np.linspace(len(data) // 16, len(data) - 1, 12).astype(int):
        damaged = bytearray(data)
        damaged[at:at + 4096] = bytes(len(damaged[at:at + 4096]))
        storage.write_bytes(bytes(damaged))
        try:
            open_recording(src)
        except InputError as exc:
            messages.append(str(exc))
    return messages


@pytest.mark.parametrize("ros2", [False, True])
def test_a_bag_damaged_anywhere_is_one_input_error_naming_it(tmp_path, ros2):
    # Session 30's fuzzing: ROS1 ReaderError ("Could not read uint8 field 'op'") and AssertionError ("assert size ==
    # 47" in rosbags' index reader), ROS2 apsw.CorruptError ("database disk image is malformed") were tracebacks.
    messages = _damaged_reads(tmp_path, ros2)
    assert messages, "no damage was noticed at all"
    bag = str(tmp_path / ("b" if ros2 else "b.bag"))
    assert all(m.startswith(bag) and "\n" not in m for m in messages)
    assert any("it is damaged" in m for m in messages)
