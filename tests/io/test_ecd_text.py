"""The numba ECD line scanner and formatter agree with each other and with Python's decimal parsing."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evpose.io import ecd_text
from evpose.io.text_table import parse_time_us


def parse(text: bytes, width=-1, height=-1):
    buf = np.frombuffer(text + b"\n", np.uint8).copy()
    n = len(text) + 1
    out = (np.empty(n, np.int64), np.empty(n, np.uint16), np.empty(n, np.uint16), np.empty(n, np.int8))
    res = ecd_text.parse_event_lines(buf, n, *out, np.iinfo(np.int64).min, width, height, ecd_text.pow10_table())
    return res, out


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 10**9), st.integers(0, 9), st.integers(0, 9), st.integers(0, 9))
def test_seconds_with_nine_decimals_round_like_decimal(us, d7, d8, d9):
    text = f"{us // 10**6}.{us % 10**6:06d}{d7}{d8}{d9}"
    (n, _, _, err, _), out = parse(f"{text} 1 2 1".encode())
    assert err == 0 and n == 1
    assert out[0][0] == parse_time_us(text)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 5000), st.integers(0, 65535), st.integers(0, 65535), st.booleans()), min_size=1, max_size=50))
def test_formatter_output_parses_back_to_the_same_events(rows):
    t = np.cumsum([r[0] for r in rows]).astype(np.int64)
    x = np.array([r[1] for r in rows], np.uint16)
    y = np.array([r[2] for r in rows], np.uint16)
    p = np.where([r[3] for r in rows], 1, -1).astype(np.int8)
    buf = np.empty(48 * len(rows), np.uint8)
    m = ecd_text.format_event_lines(t, x, y, p, buf)
    (n, used, lines, err, _), out = parse(bytes(buf[:m]).rstrip(b"\n"))
    assert err == 0 and n == len(rows) and lines == len(rows)
    for a, b in zip(out, (t, x, y, p)):
        np.testing.assert_array_equal(a[:n], b)


def test_incomplete_last_line_is_left_for_the_next_block():
    buf = np.frombuffer(b"0.1 1 2 1\n0.2 3", np.uint8).copy()
    out = (np.empty(4, np.int64), np.empty(4, np.uint16), np.empty(4, np.uint16), np.empty(4, np.int8))
    n, used, lines, err, _ = ecd_text.parse_event_lines(buf, buf.size, *out, 0, -1, -1, ecd_text.pow10_table())
    assert (n, used, lines, err) == (1, 10, 1, 0)
