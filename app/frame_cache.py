"""Display frames kept by the run-ahead: every few steps, 8-bit images, within a memory budget.

Playback and seeks are answered from these frames without touching the
tracker, so they cost a draw, not a restore-and-replay. Images are stored the
way the panels draw them: ``quantize`` gives the 8-bit value each pixel is
colour-mapped from (``floor(clip(v, 0, 1) * 255)``, the same float32 arithmetic
as the colour maps), so a frame drawn from the cache is pixel-identical to one
drawn from the float images. Large arrays are then zlib-compressed (level 1,
lossless): time surfaces are mostly empty and shrink ~30x, so a frame takes
tens of kB and every step of a long recording can be kept.
"""

from __future__ import annotations

import dataclasses
import zlib
from dataclasses import dataclass, field

import numpy as np

from app.frame import Frame


def quantize(img: np.ndarray) -> np.ndarray:
    """float image in [0, 1] -> the uint8 value the panels colour-map (uint8 input is returned as is)."""
    a = np.asarray(img)
    if a.dtype == np.uint8:
        return a
    a = np.clip(a.astype(np.float32, copy=False), 0.0, 1.0)
    return (a * np.float32(255.0)).astype(np.uint8)


def unit(img: np.ndarray) -> np.ndarray:
    """The image as float32 in [0, 1] (uint8 images are value / 255)."""
    a = np.asarray(img)
    if a.dtype == np.uint8:
        return a.astype(np.float32) / np.float32(255.0)
    return a.astype(np.float32, copy=False)


def compact(frame: Frame) -> Frame:
    """The frame with 8-bit images (a quarter of the memory, drawn identically)."""
    return dataclasses.replace(frame, ts_positive=quantize(frame.ts_positive), ts_negative=quantize(frame.ts_negative),
                               tdf=quantize(frame.tdf))


PACK_MIN_BYTES = 2048
"""Arrays at least this big are compressed in the cache; smaller ones are kept as they are, bytes."""


@dataclass(frozen=True)
class _Packed:
    """A compressed array: dtype, shape, zlib bytes, and the dtype of its first differences when delta-coded."""

    dtype: str
    shape: tuple
    data: bytes
    delta: str | None = None


def _narrowest(d: np.ndarray) -> np.dtype:
    lo, hi = (int(d.min()), int(d.max())) if d.size else (0, 0)
    for t in (np.int8, np.int16, np.int32):
        info = np.iinfo(t)
        if info.min <= lo and hi <= info.max:
            return np.dtype(t)
    return np.dtype(np.int64)


def _pack(v):
    if not (isinstance(v, np.ndarray) and v.nbytes >= PACK_MIN_BYTES):
        return v
    if v.ndim == 1 and v.dtype.kind in "iu" and v.dtype.itemsize <= 8:
        # Index lists (visible map points) are sorted: their differences fit in 8-16 bits and compress ~100x.
        d = np.diff(v.astype(np.int64), prepend=np.int64(0))
        t = _narrowest(d)
        return _Packed(v.dtype.str, v.shape, zlib.compress(d.astype(t).tobytes(), 1), t.str)
    return _Packed(v.dtype.str, v.shape, zlib.compress(np.ascontiguousarray(v).tobytes(), 1))


def _unpack(v):
    if not isinstance(v, _Packed):
        return v
    raw = zlib.decompress(v.data)
    if v.delta is not None:
        a = np.cumsum(np.frombuffer(raw, dtype=np.dtype(v.delta)), dtype=np.int64).astype(np.dtype(v.dtype))
        a.flags.writeable = False
        return a.reshape(v.shape)
    # Read-only: a frame handed out by the cache cannot be changed by whoever draws it.
    return np.frombuffer(raw, dtype=np.dtype(v.dtype)).reshape(v.shape)


def _value_nbytes(v) -> int:
    if isinstance(v, _Packed):
        return len(v.data)
    if isinstance(v, np.ndarray):
        return v.nbytes
    if hasattr(v, "t") and hasattr(v, "x"):  # EventArray
        return sum(getattr(v, a).nbytes for a in ("t", "x", "y", "p") if hasattr(v, a))
    return 0


def frame_nbytes(frame: Frame) -> int:
    """Bytes held by a frame's arrays."""
    return sum(_value_nbytes(getattr(frame, f.name)) for f in dataclasses.fields(frame))


@dataclass
class FrameCacheConfig:
    """Which steps the run-ahead keeps a display frame of, and how much memory those may take."""

    every_ms: float = field(default=20.0, metadata={"min": 1.0, "max": 1000.0, "step": 1.0, "unit": "ms"})
    """Media time between two kept frames, milliseconds. Only these steps get debug products (images,
    residuals) from the run-ahead: such a step costs ~1.9x a plain one (11.1 vs 5.7 ms CPU on the 10 s
    landing), and 1x playback shows about one step in 16 anyway. 20 ms (every 4th step at 200 Hz) keeps
    ~12 frames/s down to 0.25x speed; at or below the tracker's step every step is kept (the run-ahead
    then runs at the debug speed)."""
    budget_mb: float = field(default=512.0, metadata={"min": 16.0, "max": 8192.0, "step": 16.0, "unit": "MB"})
    """Most memory the kept frames may use; past it the frames farthest from the shown step are dropped, MB."""
    snapshot_every_ms: float = field(default=100.0, metadata={"min": 5.0, "max": 10000.0, "step": 5.0, "unit": "ms"})
    """Media time between two engine snapshots the run-ahead keeps for exact steps off the frame grid (step
    forward/back, re-runs at the current time): those restore the one before and replay at most this much,
    milliseconds (100 ms: at most 19 steps, ~0.1 s of CPU)."""
    snapshot_budget_mb: float = field(default=512.0, metadata={"min": 16.0, "max": 8192.0, "step": 16.0, "unit": "MB"})
    """Most memory the run-ahead's snapshots may use (~3.6 MB each at 346x260: 10 s at 100 ms take 360 MB);
    past it every other one is dropped, so exact steps replay up to twice as far, MB."""


class FrameCache:
    """Step index -> compact, compressed display frame on a fixed grid (``index % every == 0``)."""

    def __init__(self, every_steps: int, budget_bytes: int):
        self.every = max(int(every_steps), 1)
        self.budget = int(budget_bytes)
        self._frames: dict[int, tuple[int, dict]] = {}
        """index -> (bytes, the frame's fields with large arrays packed)."""
        self.nbytes = 0
        self.evicted = 0
        """Frames dropped to stay within the budget."""

    def __len__(self) -> int:
        return len(self._frames)

    def __contains__(self, index: int) -> bool:
        return int(index) in self._frames

    def on_grid(self, index: int) -> bool:
        return int(index) % self.every == 0

    def get(self, index: int) -> Frame | None:
        hit = self._frames.get(int(index))
        if hit is None:
            return None
        return Frame(**{name: _unpack(v) for name, v in hit[1].items()})

    def put(self, frame: Frame, near: int) -> None:
        """Keep ``frame`` (compacted, compressed); if over budget, drop the frames farthest from step ``near``."""
        if frame.index in self._frames:
            return
        fields = {f.name: _pack(getattr(compact(frame), f.name)) for f in dataclasses.fields(frame)}
        size = sum(_value_nbytes(v) for v in fields.values())
        self._frames[frame.index] = (size, fields)
        self.nbytes += size
        self._evict(near)

    def packed(self, index: int) -> tuple[int, dict] | None:
        """The stored form of a kept frame, (bytes, packed fields), for the disk cache."""
        return self._frames.get(int(index))

    def put_packed(self, index: int, entry: tuple[int, dict], near: int) -> None:
        """Keep a frame in its stored form (from the disk cache); the budget applies as in :meth:`put`."""
        if int(index) in self._frames:
            return
        self._frames[int(index)] = entry
        self.nbytes += entry[0]
        self._evict(near)

    def _evict(self, near: int) -> None:
        while self.nbytes > self.budget and len(self._frames) > 1:
            far = max(self._frames, key=lambda k: (abs(k - near), k))
            self.nbytes -= self._frames.pop(far)[0]
            self.evicted += 1

    def next_at_or_after(self, index: int, highest: int) -> Frame | None:
        """The kept frame with the smallest index in ``[index, highest]``, or None."""
        k = int(index) + (-int(index)) % self.every
        while k <= highest:
            if k in self._frames:
                return self.get(k)
            k += self.every
        return None

    def latest_at_or_before(self, index: int, lowest: int) -> Frame | None:
        """The kept frame with the largest index in ``[lowest, index]``, or None."""
        k = int(index) - int(index) % self.every
        while k >= lowest:
            if k in self._frames:
                return self.get(k)
            k -= self.every
        return None

    def clear(self) -> None:
        self._frames.clear()
        self.nbytes = 0
