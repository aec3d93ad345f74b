"""Small whitespace-separated numeric tables (IMU, poses, calibration) with line-exact errors.

These files hold thousands, not millions, of lines, so a plain Python loop is
fast enough and lets every problem name its line. Timestamps are parsed from
their decimal text into int64 microseconds exactly (no float rounding).
"""

from __future__ import annotations

import enum
import math
from decimal import Decimal, InvalidOperation
from pathlib import Path

import numpy as np

from evpose.errors import InputError
from evpose.io.paths import not_a_file


class TimeUnit(str, enum.Enum):
    """Unit of the first column of a table."""

    SECONDS = "s"
    MICROSECONDS = "us"
    NANOSECONDS = "ns"


_SCALE = {TimeUnit.SECONDS: Decimal(1_000_000), TimeUnit.MICROSECONDS: Decimal(1), TimeUnit.NANOSECONDS: Decimal("0.001")}


def parse_time_us(text: str, unit: TimeUnit = TimeUnit.SECONDS) -> int:
    """Decimal text in ``unit`` -> int64 microseconds, rounded half-up; ValueError if not a finite number."""
    try:
        d = Decimal(text)
    except InvalidOperation:
        raise ValueError(text) from None
    if not d.is_finite():
        raise ValueError(text)
    us = (d * _SCALE[unit]).to_integral_value(rounding="ROUND_HALF_UP")
    if abs(us) >= 2**63:
        raise ValueError(text)
    return int(us)


def read_table(path: str | Path, n_cols: int, unit: TimeUnit = TimeUnit.SECONDS, what: str = "line", delimiter: str | None = None,
               line_numbers: list[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Read ``t v1 .. v{n_cols-1}`` rows; returns (t int64 us, values float64 (N, n_cols-1)).

    Blank lines and ``#`` comments are skipped; times must strictly increase.
    Every problem raises :class:`InputError` naming the file and line. ``line_numbers``, if given, receives
    each row's line number, so a caller's own checks can name the line too.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(path, not_a_file(path))
    ts: list[int] = []
    rows: list[list[float]] = []
    try:
        fh = open(path, encoding="utf-8")
    except OSError as exc:
        raise InputError(path, f"cannot read ({exc.strerror})") from None
    with fh:
        try:
            for lineno, line in enumerate(fh, start=1):
                s = line.strip()
                if not s or s.startswith("#"):
                    continue
                parts = s.split(delimiter) if delimiter else s.split()
                parts = [q.strip() for q in parts]
                if len(parts) != n_cols:
                    raise InputError(path, f"expected {n_cols} values, got {len(parts)}", f"line {lineno}")
                try:
                    t = parse_time_us(parts[0], unit)
                except ValueError:
                    raise InputError(path, f"timestamp {parts[0]!r} is not a finite number", f"line {lineno}") from None
                try:
                    vals = [float(v) for v in parts[1:]]
                except ValueError:
                    raise InputError(path, "value is not a number", f"line {lineno}") from None
                if not all(math.isfinite(v) for v in vals):
                    raise InputError(path, "NaN or infinite value", f"line {lineno}")
                if ts and t <= ts[-1]:
                    raise InputError(path, f"timestamp {parts[0]} does not increase (timestamps must be strictly increasing)", f"line {lineno}")
                ts.append(t)
                rows.append(vals)
                if line_numbers is not None:
                    line_numbers.append(lineno)
        except UnicodeDecodeError:
            raise InputError(path, "not a text file") from None
    values = np.asarray(rows, dtype=np.float64).reshape(-1, n_cols - 1)
    return np.asarray(ts, dtype=np.int64), values


def format_time(t_us: np.ndarray, unit: TimeUnit = TimeUnit.SECONDS) -> list[str]:
    """int64 microseconds -> exact decimal strings in ``unit`` (seconds with 6 decimals)."""
    out = []
    for t in np.asarray(t_us, dtype=np.int64).tolist():
        if unit is TimeUnit.MICROSECONDS:
            out.append(str(t))
        elif unit is TimeUnit.NANOSECONDS:
            out.append(str(t * 1000))
        else:
            sign = "-" if t < 0 else ""
            a = abs(t)
            out.append(f"{sign}{a // 1_000_000}.{a % 1_000_000:06d}")
    return out


def write_table(fh, t_us: np.ndarray, values: np.ndarray, unit: TimeUnit = TimeUnit.SECONDS, header: str | None = None) -> None:
    """Write rows ``t v...`` with values in ``repr`` precision (round-trips float64 exactly)."""
    if header:
        fh.write(f"# {header}\n")
    for ts, row in zip(format_time(t_us, unit), np.asarray(values, dtype=np.float64).tolist()):
        fh.write(ts + " " + " ".join(repr(v) for v in row) + "\n")
