"""Run a batch generator one step ahead in a worker thread, so parsing overlaps with writing.

The numba scanners release the GIL (``nogil=True``), so on two cores the text
parser and the HDF5/Blosc writer run at the same time. The queue depth bounds
memory; batch order is preserved, so output stays bit-identical.
"""

from __future__ import annotations

import queue
import threading
from typing import Iterable, Iterator, TypeVar

T = TypeVar("T")
_DONE = object()


class _Raised:
    def __init__(self, exc: BaseException):
        self.exc = exc


def prefetch(batches: Iterable[T], depth: int = 2) -> Iterator[T]:
    """Yield the items of ``batches``, produced by a worker thread at most ``depth`` items ahead.

    An exception in the producer is re-raised in the consumer; if the consumer
    stops early, the producer is stopped and closed.
    """
    q: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()
    source = iter(batches)

    def put(item) -> bool:
        while not stop.is_set():
            try:
                q.put(item, timeout=0.05)
                return True
            except queue.Full:
                continue
        return False

    def work() -> None:
        try:
            for item in source:
                if not put(item):
                    return
            put(_DONE)
        except BaseException as exc:  # handed to the consumer, which re-raises it
            put(_Raised(exc))

    worker = threading.Thread(target=work, name="evpose-prefetch", daemon=True)
    worker.start()
    try:
        while True:
            item = q.get()
            if item is _DONE:
                return
            if isinstance(item, _Raised):
                raise item.exc
            yield item
    finally:
        stop.set()
        worker.join()
        close = getattr(source, "close", None)
        if close is not None:
            close()
