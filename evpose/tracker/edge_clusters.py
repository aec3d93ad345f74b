"""Per-edge shared offsets in the events' normal equations (issue 7, session 37): the events of one map edge share an
offset beyond their class lead, so an edge counts as one measurement of its mean, not as many as it fires events.

Each event's residual is modelled as ``r_i = J_i xi + o_e + eps_i`` with ``o_e`` an offset shared by the events of its
edge ``e`` (variance ``edge_sigma_px^2``) and ``eps_i`` its own (``event_sigma_px^2``). Generalised least squares
over an edge's ``n`` events then weighs ``(I - rho 1 1^T)`` instead of ``I`` (``rho = s_e^2 / (s^2 + n s_e^2)``), so
the normal equations lose ``rho g g^T`` and ``rho s g`` per edge (``g`` = the edge's summed weighted Jacobians, ``s``
its summed weighted residuals): an edge's mean holds the pose with at most ``1 / s_e^2`` however many events it
fires, what varies along it (its direction, its length) keeps its full weight. An "edge" here is the map points of
one surface region whose 3D edge normals point the same way (one of six axis directions) inside one cube of
``cell_m``: a box's rim side, a crate's foot.

Why (session 37, ``/tmp/s37/rt37/feat.py`` on session 32's per-event offsets from the simulator's true edges at the
true pose): per true segment the events' mean offset spreads by 0.08-0.12 px beyond its polarity's mean at both
sensors (so 1.44x the angle at 240x180) while an event's own spread is ~0.3 px; session 33 found the registrations'
ridge swing (shift along x against tilt about y) early in the flight set by 6-8 such edges adding up, each weighed by
its tens of events.

Off: neither helps (``full`` from ground truth through the CLI, ``/tmp/s37/rt37/run.sh`` and ``cmp.py``, cached
240x180 2 s landings, paired against main's defaults; mean ATE mm, change +- standard error, seeds better, ARE deg;
``cell_m`` 0.5, ``event_sigma_px`` 0.3). ``edge_sigma_px`` 0.1 / 0.05 with ``in_covariance`` (seeds 0-8: 4.924 ->
5.399, +0.475 +- 0.114, 0 of 9, ARE 0.0580 -> 0.0629; 5.112, +0.188 +- 0.072, 2 of 9): the events' covariance grows
along every edge's mean, so the field takes over; without it (the pose alone corrected; seeds 0-11: 4.916 -> 5.004,
+0.088 +- 0.049, 4 of 12, ARE 0.0582 -> 0.0602; 4.994, +0.078 +- 0.047, 3 of 12). ``edge_huber_px`` 0.15 (seeds
0-23): 5.060 -> 5.096 (+0.037 +- 0.052, 10 of 24), ARE 0.0597 -> 0.0595; 0.08 (seeds 0-20): 4.986 -> 5.086 (+0.100 +-
0.069, 8 of 21). From the truth (``/tmp/s37/rt37/oracle.py``
with ``ORACLE=1``: every prediction, hence the prior, the true pose; ``slow.py``: RMS of the 50-update moving mean of
the camera-frame error; seeds 0-3) both look better on every axis: the events' slow x / y / z 4.21 / 2.25 / 2.21 mm,
ridge ``(x - h ry) / 2`` 3.94 mm -> 3.70 / 1.86 / 1.74, 3.45 (``edge_sigma_px`` 0.1 without ``in_covariance``) and
3.86 / 2.14 / 2.13, 3.63 (``edge_huber_px`` 0.15); the combined registration's ridge 3.17 -> 2.85 / 3.01 mm, its whole
RMS x 5.19 -> 4.79 / 4.84 mm. That gain comes through the events' prior, which sits at the truth there and at the
prediction in a run: with the prior off (``prior_residual_px`` 0) the events' slow ridge / x read 8.20 / 8.45 mm by
default and 8.24 / 8.52 with ``edge_sigma_px`` 0.1 (y / z 5.89 / 4.42 -> 5.29 / 4.06). So the correction moves weight
from the events to their prior rather than taking out their bias. Weakening the prior instead loses more
(``prior_residual_px`` 1.0 with ``edge_sigma_px`` 0.1, seeds 0-8 and 12-21: 5.009 -> 5.424, +0.415 +- 0.134, 6 of
19).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np


@dataclass
class EdgeClusterConfig:
    """Per-edge shared offsets in the events' registration (see the module; off by default)."""

    edge_sigma_px: float = field(default=0.0, metadata={"min": 0.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """Spread of the offset the events of one edge share beyond their class lead, pixels (0 = off: every event
    independent)."""
    event_sigma_px: float = field(default=0.3, metadata={"min": 0.01, "max": 2.0, "step": 0.01, "unit": "px"})
    """Spread of one event about its edge's shared offset, pixels."""
    cell_m: float = field(default=0.5, metadata={"min": 0.05, "max": 10.0, "step": 0.05, "unit": "m"})
    """Side of the cubes that split one region's edge points of one direction into edges, metres."""
    edge_huber_px: float = field(default=0.0, metadata={"min": 0.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """Huber scale on each edge's mean residual, pixels: from the second Gauss-Newton pass on, the events of an edge
    whose events' mean distance (at the previous pass) exceeds this are weighed down by this over it (0 = off)."""
    in_covariance: bool = True
    """The events' covariance from the corrected normal equations too; False = only their pose (the Gauss-Newton
    steps) is corrected, the covariance stays that of independent events."""


_NO_SWJ = np.zeros((0, 6))
_NO_SCALE = np.zeros(0)
"""Placeholders of the events' kernel's optional per-point sums and weights (never written)."""


def edge_ids_for(config: EdgeClusterConfig, points, edge_normals, region_id) -> np.ndarray | None:
    """:func:`edge_cluster_ids` of a map when ``config`` turns either correction on, else None."""
    if float(config.edge_sigma_px) > 0 or float(config.edge_huber_px) > 0:
        return edge_cluster_ids(points, edge_normals, region_id, float(config.cell_m))
    return None


class EdgeTerms:
    """One registration's per-edge terms: the kernel's ``swj`` (per-point weighted Jacobians) and ``pscale``
    (per-point weights) inputs, placeholders when off, and what follows each pass."""

    def __init__(self, config: EdgeClusterConfig, ids: np.ndarray | None, used: np.ndarray):
        """``ids`` the whole map's edge ids (None = off), ``used`` the registered points' indices."""
        self.config = config
        on = ids is not None
        self.cluster = ids[used] if on else None
        self.gls = on and float(config.edge_sigma_px) > 0
        self.swj = np.zeros((used.size, 6)) if self.gls else _NO_SWJ
        self.pscale = np.ones(used.size) if on and float(config.edge_huber_px) > 0 else _NO_SCALE

    def after_pass(self, last: bool, sw, swr, H, b) -> None:
        """After a pass: the next pass's edge weights, and the shared offsets out of ``H`` / ``b`` (not on the ``last``
        pass, which gives the covariance, unless ``in_covariance``)."""
        c = self.config
        if self.pscale.size:
            edge_weights(self.cluster, sw, swr, self.pscale, float(c.edge_huber_px))
        if self.gls and (not last or c.in_covariance):
            shared_offset_correction(self.cluster, sw, swr, self.swj, float(c.edge_sigma_px) ** 2, float(c.event_sigma_px) ** 2, H, b)


def edge_cluster_ids(points: np.ndarray, edge_normals: np.ndarray, region_id: np.ndarray | None, cell_m: float) -> np.ndarray:
    """(N,) int64 edge id per map point: the same for points of one region (``region_id``, -1 / None = none), one
    dominant signed axis of their edge normal (``edge_normals`` (N, 3); zero = its own id) and one ``cell_m`` cube."""
    p = np.asarray(points, np.float64)
    n = np.asarray(edge_normals, np.float64)
    count = p.shape[0]
    if count == 0:
        return np.zeros(0, np.int64)
    axis = np.argmax(np.abs(n), axis=1)
    sign = np.take_along_axis(n, axis[:, None], axis=1)[:, 0] > 0
    direction = axis * 2 + sign
    unknown = ~np.any(n != 0, axis=1)
    cell = np.floor(p / float(cell_m)).astype(np.int64)
    reg = np.full(count, -1, np.int64) if region_id is None else np.asarray(region_id, np.int64)
    key = np.column_stack([reg, direction, cell])
    key[unknown] = np.column_stack([np.full(int(unknown.sum()), -2, np.int64), np.flatnonzero(unknown), np.zeros((int(unknown.sum()), 3), np.int64)])
    _, ids = np.unique(key, axis=0, return_inverse=True)
    return np.ascontiguousarray(ids.reshape(-1), np.int64)


@nb.njit(cache=True)
def _edge_sums(cluster, sw, swr):  # pragma: no cover
    """Per edge id (0 .. max): the summed robust weights and weighted residuals of its points."""
    c_max = 0
    for k in range(cluster.shape[0]):
        if cluster[k] > c_max:
            c_max = cluster[k]
    n = np.zeros(c_max + 1)
    s = np.zeros(c_max + 1)
    for k in range(cluster.shape[0]):
        n[cluster[k]] += sw[k]
        s[cluster[k]] += swr[k]
    return n, s


@nb.njit(cache=True)
def shared_offset_correction(cluster, sw, swr, swj, edge_var, event_var, H, b):  # pragma: no cover
    """Takes each edge's shared offset out of the events' normal equations ``H`` / ``b`` in place (see the module):
    ``cluster`` (M,) the edge ids of the used points (0 .. C-1), ``sw`` / ``swr`` / ``swj`` (M,) / (M,) / (M, 6)
    each point's summed robust weights, weighted residuals and weighted Jacobians, ``edge_var`` / ``event_var`` the
    two variances (px^2)."""
    n, s = _edge_sums(cluster, sw, swr)
    g = np.zeros((n.shape[0], 6))
    for k in range(cluster.shape[0]):
        for a in range(6):
            g[cluster[k], a] += swj[k, a]
    for c in range(n.shape[0]):
        if n[c] <= 0.0:
            continue
        # Per-event GLS weight on the unit-noise scale of H: (I - rho 1 1^T) / event_var, H and b in event_var units.
        rho = edge_var / (event_var + n[c] * edge_var)
        for a in range(6):
            b[a] -= rho * s[c] * g[c, a]
            for d in range(6):
                H[a, d] -= rho * g[c, a] * g[c, d]


@nb.njit(cache=True)
def edge_weights(cluster, sw, swr, pscale, huber):  # pragma: no cover
    """Each used point's weight ``pscale`` (M,) for the next pass: ``huber / |mean|`` where its edge's mean residual
    (from the points' summed weights ``sw`` and weighted residuals ``swr`` of this pass, which include the current
    ``pscale``) exceeds ``huber``, else 1."""
    n, s = _edge_sums(cluster, sw, swr)
    for k in range(cluster.shape[0]):
        c = cluster[k]
        a = abs(s[c]) / n[c] if n[c] > 0.0 else 0.0
        pscale[k] = huber / a if a > huber else 1.0
