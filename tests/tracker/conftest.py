"""Shared set-up of the tracker tests."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from evpose.core.contour_map import ContourMap


@pytest.fixture(scope="module")
def landing_head(sim_landing_small):
    """``landing_head(seconds)``: the first ``seconds`` of the small simulated landing and a map sampled along its true
    edges every 2 cm."""

    def head(seconds: float):
        res = sim_landing_small
        rec = res.recording
        pts = []
        for a, b in res.edges:
            n = max(int(np.linalg.norm(b - a) / 0.02), 1)
            pts.append(a + (b - a) * (np.arange(n) / n)[:, None])
        t0 = int(rec.events.t[0])
        short = dataclasses.replace(rec, events=rec.events.time_window(t0, t0 + int(seconds * 1e6)))
        return short, ContourMap.from_points(np.concatenate(pts))

    return head
