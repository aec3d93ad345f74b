"""The wrong-map rules: no registration from the start for ``acquire_s`` seconds (one registration clears it), and
registrations no better than chance over that window."""

import numpy as np

from evpose.tracker.map_acquisition import (MapAcquisitionConfig, chance_evidence, chance_mismatch, chance_problem, chance_z,
                                            map_mismatch, mismatch_problem, registered, unacquired_s)


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


def _counts(inliers: int, points: int, hits: int, samples: int = 800) -> dict:
    return {"registered": 1, "inliers": inliers, "points_in_image": points, "chance_hits": hits, "chance_samples": samples}


def test_an_inlier_count_is_scored_against_its_chance_level():
    assert chance_z({"registered": 1, "inliers": 40}) is None  # no chance counts (past the window, older caches)
    assert chance_z(_counts(50, 100, 400)) == 0.0  # half the points, half the displaced samples: chance
    assert abs(chance_z(_counts(60, 100, 200)) - 35 / np.sqrt(18.75)) < 1e-12
    assert chance_z(_counts(20, 100, 0)) == 20.0  # no chance at all: each inlier counts one (floored spread)


def test_a_map_at_chance_level_under_dense_events_is_reported_once_the_window_is_spanned():
    # Registered every time, as a wrong map does where events cover the image (flicker), but no better than chance.
    steps = [(5_000 * k, _counts(300, 500, 480)) for k in range(201)]
    assert chance_mismatch(steps[:150], 0) is None  # 0.745 s: not yet
    z = chance_mismatch(steps, 0)
    assert z is not None and abs(z - chance_z(_counts(300, 500, 480))) < 1e-12
    assert chance_mismatch(steps[:60], 0, finished=True) == z  # a shorter recording, once it ends
    assert chance_mismatch(steps, 0, acquire_s=0.0) is None
    assert chance_mismatch(steps, 0, config=MapAcquisitionConfig(min_chance_z=0.0)) is None
    assert "best 20-update median" in chance_problem(z, 1.0, "rec.h5") and "rec.h5" in chance_problem(z, 1.0, "rec.h5")


def test_a_right_map_passes_on_its_best_run_even_if_it_loses_the_track_later():
    good = [(5_000 * k, _counts(200, 500, 80)) for k in range(40)]
    lost = [(5_000 * k, _counts(10, 500, 80)) for k in range(40, 201)]
    assert chance_evidence(good + lost) > MapAcquisitionConfig().min_chance_z
    assert chance_mismatch(good + lost, 0) is None
    assert chance_mismatch(lost, 0) is not None


def test_steps_without_chance_counts_are_not_judged():
    steps = [(5_000 * k, {"registered": 1, "inliers": 1, "points_in_image": 500}) for k in range(201)]
    assert chance_evidence(steps) is None and chance_mismatch(steps, 0) is None
