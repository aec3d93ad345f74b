"""The wrong-map rule: no registration from the start for ``acquire_s`` seconds; one registration clears it."""

from evpose.tracker.map_acquisition import map_mismatch, mismatch_problem, registered, unacquired_s


def test_a_map_never_registered_against_is_reported_once_the_window_is_reached():
    steps = [(1_000_000 + 5_000 * k, {"registered": 0}) for k in range(201)]  # 0 .. 1.0 s after the start
    assert map_mismatch(steps[:200], 1_000_000) is None  # 0.995 s: not yet
    assert map_mismatch(steps, 1_000_000) == 1.0
    assert map_mismatch(steps, 1_000_000, acquire_s=0.0) is None  # 0 = never give up


def test_one_registered_update_means_the_map_fits():
    steps = [(5_000 * k, {"registered": int(k == 150)}) for k in range(400)]
    assert unacquired_s(steps, 0) is None and map_mismatch(steps, 0) is None


def test_steps_without_the_count_count_as_registered_and_no_steps_say_nothing():
    assert registered({}) and not registered({"registered": 0})
    assert unacquired_s([], 0) is None


def test_a_recording_shorter_than_the_window_that_never_registered_is_reported_once_finished():
    steps = [(5_000 * k, {"registered": 0}) for k in range(60)]  # 0.3 s
    assert map_mismatch(steps, 0) is None
    assert map_mismatch(steps, 0, finished=True) == 0.295
    assert map_mismatch(steps, 0, acquire_s=0.0, finished=True) is None


def test_the_mismatch_problem_names_the_recording_the_window_and_the_reason():
    assert mismatch_problem(0.125, "rec.h5", "coasting") == ("no update registered against this map in the first 0.12 s of rec.h5"
                                                             " (coasting): is it this recording's map, in its frame?")
