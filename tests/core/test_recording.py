"""Recording: sensor size resolution, validation and the info summary."""

import numpy as np
import pytest

from evpose.core.camera import CameraCalibration
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.errors import InputError


def test_sensor_size_comes_from_calibration_then_metadata_then_unknown():
    ev = EventArray.from_arrays([0, 1], [0, 1], [0, 1], [0, 1])
    cal = CameraCalibration(64, 48, 50.0, 50.0, 32.0, 24.0)
    assert Recording(ev, calibration=cal, metadata={"width": 1, "height": 1}).sensor_size == (64, 48)
    assert Recording(ev, metadata={"width": 240, "height": 180}).sensor_size == (240, 180)
    assert Recording(ev).sensor_size is None


def test_validate_checks_events_against_the_sensor_size():
    ev = EventArray.from_arrays([0, 1], [0, 300], [0, 1], [0, 1])
    with pytest.raises(InputError, match="x=300 is outside the sensor width 240"):
        Recording(ev, metadata={"width": 240, "height": 180}).validate()


def test_summary_reports_counts_rates_and_duration():
    t = np.arange(0, 2_000_001, 1000)
    ev = EventArray.from_arrays(t, np.zeros(t.size), np.zeros(t.size), np.arange(t.size) % 2)
    imu = ImuSamples.from_arrays(t[::2], np.zeros((t[::2].size, 3)), np.zeros((t[::2].size, 3)))
    s = Recording(ev, imu=imu).summary()
    assert s["events"] == t.size
    assert s["duration_s"] == pytest.approx(2.0)
    assert s["event_rate_hz"] == pytest.approx(t.size / 2.0)
    assert s["imu_rate_hz"] == pytest.approx(500.0)
    assert s["positive_share"] == pytest.approx(0.5, abs=1e-3)
    assert s["ground_truth_poses"] == 0 and s["calibration"] is None


@pytest.mark.parametrize("width, height", [("big", 260), (-5, 260), (346.5, 260), (True, 260), (346, 10**6)])
def test_metadata_sensor_size_that_is_not_one_is_an_input_error_naming_the_file(width, height):
    # A width of "big" in a file's metadata ended in int()'s ValueError traceback.
    rec = Recording(EventArray.empty(), metadata={"width": width, "height": height}, source="rec.h5")
    with pytest.raises(InputError, match=r"rec.h5: metadata width/height .* is not a sensor size \(1..65536 pixels\)"):
        rec.sensor_size
