"""SlamRun's accounting of the recording's time."""

import pytest

from evpose.slam import SlamFailure, SlamRun, SlamStatus, SlamStepResult
from evpose.slam.atlas import Atlas


def _result(t_us, status, failure=SlamFailure.NONE, blank_us=0):
    return SlamStepResult(t_us, status, failure=failure, counts={"blank_us": blank_us})


def test_untracked_time_is_split_by_failure_with_the_blank_part_apart():
    results = [
        _result(100_000, SlamStatus.NOT_INITIALISED, SlamFailure.INITIALISING),
        _result(200_000, SlamStatus.OK),
        _result(500_000, SlamStatus.COASTING, SlamFailure.STARVED, blank_us=250_000),  # 0.3 s span, 0.25 s of it blank
        _result(600_000, SlamStatus.COASTING, SlamFailure.REJECTED),
        _result(700_000, SlamStatus.LOST, SlamFailure.STARVED),
        _result(900_000, SlamStatus.OK, blank_us=150_000),  # a tracked MCI's blank time stays tracked
    ]
    run = SlamRun(results, Atlas(), duration_s=1.0, wall_s=0.0, start_us=0)
    by_failure = run.time_by_failure_s()
    assert by_failure == pytest.approx({"blank": 0.25, "initialising": 0.1, "rejected": 0.1, "starved": 0.15})
    by_status = run.time_by_status_s()
    untracked = sum(v for k, v in by_status.items() if k not in ("ok", "none"))
    assert sum(by_failure.values()) == pytest.approx(untracked)


def test_blank_time_never_exceeds_the_span_its_mci_owns():
    run = SlamRun([_result(50_000, SlamStatus.COASTING, SlamFailure.STARVED, blank_us=80_000)], Atlas(), 0.1, 0.0, 0)
    assert run.time_by_failure_s() == pytest.approx({"blank": 0.05})
