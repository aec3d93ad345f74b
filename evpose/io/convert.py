"""Stream any supported recording into the evpose HDF5 format with bounded memory and a progress bar."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

from evpose.errors import InputError
from evpose.io.h5 import H5RecordingWriter, H5WriteConfig
from evpose.io.open import open_stream
from evpose.io.prefetch import prefetch


@dataclass(frozen=True)
class ConvertResult:
    """What a conversion did."""

    events: int
    """Events written, count."""
    seconds: float
    """Wall time of the conversion, s."""
    source_format: str
    """Recognised input format."""

    @property
    def events_per_s(self) -> float:
        return self.events / self.seconds if self.seconds > 0 else 0.0


def convert_to_h5(
    src: str | Path,
    dst: str | Path,
    width: int | None = None,
    height: int | None = None,
    config: H5WriteConfig = H5WriteConfig(),
    progress: bool | None = None,
    threaded: bool = True,
    **options,
) -> ConvertResult:
    """Convert ``src`` to ``dst`` (evpose HDF5), atomically; ``dst`` may not be ``src``.

    ``progress``: True/False forces the tqdm bar on stderr on/off; None shows
    it only when stderr is a terminal. Event batches are validated as they
    stream; any problem aborts and leaves no output behind. ``threaded`` reads
    the next batch in a worker thread while the current one is written (same
    output, faster when a second core is free).
    """
    src, dst = Path(src), Path(dst)
    if dst.exists() and src.exists() and dst.resolve() == src.resolve():
        raise InputError(dst, "refusing to overwrite the input")
    if dst.is_dir():
        raise InputError(dst, "output is a folder; give a .h5 file name")
    t0 = time.perf_counter()
    stream = open_stream(src, width, height, **options)
    ctx = stream.context
    from tqdm import tqdm

    disable = (not sys.stderr.isatty()) if progress is None else (not progress)
    bar = tqdm(total=stream.progress_total, unit=stream.progress_unit, unit_scale=True, desc=f"convert {src.name}", file=sys.stderr, disable=disable, mininterval=0.5)
    try:
        with H5RecordingWriter(dst, inputs=(src,), config=config) as writer:
            metadata = dict(ctx.metadata)
            metadata.setdefault("source_format", stream.format.value)
            writer.set_metadata(metadata)
            writer.set_calibration(ctx.calibration)
            writer.set_imu(ctx.imu)
            writer.set_ground_truth(ctx.ground_truth)
            # Every reader validates its batches (order, bounds, polarity) and names the bad record.
            batches = stream.batches(bar.update)
            for batch in prefetch(batches) if threaded else batches:
                writer.append_events(batch, source=str(src))
            n = writer.events_written
            if n == 0:
                raise InputError(src, "contains no events")
    finally:
        bar.close()
    return ConvertResult(n, time.perf_counter() - t0, stream.format.value)
