"""_trace_chains: every edge pixel once, in 8-connected order, open curves from an end."""

from __future__ import annotations

import numpy as np

from evpose.mapping.edge_chains import _trace_chains


def _chains(img):
    rows, cols, starts = _trace_chains(img.astype(np.uint8))
    return [np.stack([rows[a:b], cols[a:b]], axis=1) for a, b in zip(starts[:-1], starts[1:])]


def test_a_line_and_a_loop_give_two_ordered_chains_covering_every_pixel():
    img = np.zeros((30, 40), np.uint8)
    img[5, 3:20] = 1  # open line
    img[15:25, 25] = img[15:25, 34] = 1  # square loop
    img[15, 25:35] = img[24, 25:35] = 1
    chains = _chains(img)
    assert len(chains) == 2
    assert sum(len(c) for c in chains) == int(img.sum())
    for c in chains:
        steps = np.abs(np.diff(c, axis=0)).max(axis=1)
        assert np.all(steps == 1)  # consecutive pixels are 8-neighbours
    line = chains[0]
    assert tuple(line[0]) in {(5, 3), (5, 19)} and tuple(line[-1]) in {(5, 3), (5, 19)}


def test_a_diagonal_curve_is_one_chain():
    img = np.zeros((20, 20), np.uint8)
    for i in range(15):
        img[2 + i, 2 + i] = 1
    chains = _chains(img)
    assert len(chains) == 1 and len(chains[0]) == 15


def test_empty_map_gives_no_chain():
    rows, cols, starts = _trace_chains(np.zeros((5, 5), np.uint8))
    assert rows.size == 0 and starts.size == 1
