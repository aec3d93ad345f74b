"""prefetch: same items in the same order, producer errors re-raised, early stop closes the producer."""

import threading

import pytest

from evpose.io.prefetch import prefetch


def test_yields_every_item_in_order():
    assert list(prefetch(iter(range(1000)), depth=3)) == list(range(1000))


def test_producer_exception_reaches_the_consumer():
    def gen():
        yield 1
        raise ValueError("bad line 7")

    it = prefetch(gen())
    assert next(it) == 1
    with pytest.raises(ValueError, match="bad line 7"):
        next(it)


def test_consumer_stopping_early_stops_and_closes_the_producer():
    closed = threading.Event()

    def gen():
        try:
            for i in range(10**9):
                yield i
        finally:
            closed.set()

    it = prefetch(gen())
    assert next(it) == 0
    it.close()
    assert closed.is_set()
    assert not any(t.name == "evpose-prefetch" and t.is_alive() for t in threading.enumerate())
