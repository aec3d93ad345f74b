"""EventArray: dtypes, polarity conversion, windows, validation."""

import numpy as np
import pytest

from evpose.core.events import EventArray
from evpose.errors import InputError


def make(n=100, seed=0):
    rng = np.random.default_rng(seed)
    return EventArray.from_arrays(np.sort(rng.integers(0, 10_000, n)), rng.integers(0, 64, n), rng.integers(0, 48, n), rng.integers(0, 2, n))


def test_from_arrays_converts_to_canonical_dtypes_and_maps_zero_one_polarity():
    ev = EventArray.from_arrays([1, 2], [3, 4], [5, 6], [0, 1])
    assert (ev.t.dtype, ev.x.dtype, ev.y.dtype, ev.p.dtype) == (np.int64, np.uint16, np.uint16, np.int8)
    assert ev.p.tolist() == [-1, 1]
    assert EventArray.from_arrays([1, 2], [0, 0], [0, 0], [-1, 1]).p.tolist() == [-1, 1]
    assert EventArray.from_arrays([1, 2], [0, 0], [0, 0], np.array([True, False])).p.tolist() == [1, -1]


def test_from_arrays_rejects_columns_of_different_length():
    with pytest.raises(ValueError):
        EventArray.from_arrays([1, 2], [3], [5, 6], [0, 1])


def test_time_window_equals_boolean_selection():
    ev = make(500)
    w = ev.time_window(2000, 7000)
    mask = (ev.t >= 2000) & (ev.t < 7000)
    np.testing.assert_array_equal(w.t, ev.t[mask])
    np.testing.assert_array_equal(w.x, ev.x[mask])


def test_concatenate_and_empty():
    ev = make(10)
    both = EventArray.concatenate([ev[:4], ev[4:]])
    np.testing.assert_array_equal(both.t, ev.t)
    assert len(EventArray.concatenate([])) == 0
    assert EventArray.empty().duration_us == 0


def test_validate_names_the_first_unsorted_event():
    ev = EventArray.from_arrays([1, 5, 3], [0, 0, 0], [0, 0, 0], [1, 1, 1])
    with pytest.raises(InputError, match=r"f.txt: event 2: timestamp 3 us is earlier"):
        ev.validate(source="f.txt")


def test_validate_names_pixels_outside_the_sensor():
    ev = EventArray.from_arrays([1, 2], [0, 64], [0, 0], [1, 1])
    with pytest.raises(InputError, match="event 1: x=64 is outside the sensor width 64"):
        ev.validate(64, 48)
    ev = EventArray.from_arrays([1, 2], [0, 0], [48, 0], [1, 1])
    with pytest.raises(InputError, match="event 0: y=48 is outside the sensor height 48"):
        ev.validate(64, 48)


def test_validate_rejects_polarity_other_than_plus_minus_one():
    ev = EventArray(np.array([1], np.int64), np.zeros(1, np.uint16), np.zeros(1, np.uint16), np.array([0], np.int8))
    with pytest.raises(InputError, match="polarity 0"):
        ev.validate()
