"""ImuSamples: rate, windows and validation."""

import numpy as np
import pytest

from evpose.core.imu import ImuSamples
from evpose.errors import InputError


def test_rate_is_the_median_sample_rate():
    t = np.arange(0, 1_000_000, 1000)
    imu = ImuSamples.from_arrays(t, np.zeros((t.size, 3)), np.zeros((t.size, 3)))
    assert imu.rate_hz == pytest.approx(1000.0)
    assert ImuSamples.empty().rate_hz == 0.0


def test_time_window_selects_half_open_interval():
    t = np.arange(10) * 100
    imu = ImuSamples.from_arrays(t, np.arange(30).reshape(10, 3), np.zeros((10, 3)))
    assert imu.time_window(200, 500).t.tolist() == [200, 300, 400]


def test_validate_rejects_repeated_timestamps_and_nan():
    imu = ImuSamples.from_arrays([0, 1, 1], np.zeros((3, 3)), np.zeros((3, 3)))
    with pytest.raises(InputError, match="IMU sample 2: timestamp 1 us does not increase"):
        imu.validate()
    acc = np.zeros((2, 3))
    acc[1, 2] = np.inf
    with pytest.raises(InputError, match="IMU sample 1: NaN or infinite"):
        ImuSamples.from_arrays([0, 1], acc, np.zeros((2, 3))).validate()


def test_huge_sample_is_named_with_its_magnitude_and_no_overflow_warning():
    import warnings

    acc = np.zeros((3, 3))
    acc[2, 1] = 1e300  # np.linalg.norm overflowed here and numpy printed a RuntimeWarning before the error line
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError, match=r"IMU sample 2: acceleration 1e\+300 m/s\^2 is beyond any IMU's range"):
            ImuSamples.from_arrays([0, 1, 2], acc, np.zeros((3, 3))).validate()
