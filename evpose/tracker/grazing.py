"""Map points whose surface the camera sees at a grazing angle, and those on a crease between two surfaces: their OFF
edges' events trail further behind the edge than a face-on surface's plain edge (see
``EventRegistrationConfig.grazing_max_cos`` and ``crease_radius_m``)."""

from __future__ import annotations

import numba
import numpy as np
from scipy.spatial import cKDTree


@numba.njit(cache=True)
def _grazing_mask(normals, normal_index, points, point_index, centre, max_cos):  # pragma: no cover - numba
    # One pass over the gathered rows: numpy's gathers and temporaries cost ~60 us per call on ~900 points, twice per
    # update (session 18 profile). The sums run in numpy's order (einsum / norm over three terms), so the mask is the same.
    out = np.zeros(normal_index.size, np.bool_)
    for r in range(normal_index.size):
        i, j = normal_index[r], point_index[r]
        n0, n1, n2 = normals[i, 0], normals[i, 1], normals[i, 2]
        d0, d1, d2 = points[j, 0] - centre[0], points[j, 1] - centre[1], points[j, 2] - centre[2]
        if not n0 * n0 + n1 * n1 + n2 * n2 > 0.25:
            continue
        cos = abs(n0 * d0 + n1 * d1 + n2 * d2) / max(np.sqrt(d0 * d0 + d1 * d1 + d2 * d2), 1e-12)
        out[r] = cos < max_cos
    return out


@numba.njit(cache=True)
def _point_leads(used, crease, edge_normals, points, plane_normals, centre, on_lead, off_lead, crease_on, crease_off,
                 beyond_off, max_cos, grazing_on, grazing_off, on, off):  # pragma: no cover - numba
    # The events' ON / OFF lead per used point in one pass (:meth:`EventRegistration._leads
    # <evpose.tracker.event_registration.EventRegistration._leads>`): its numpy gathers, masks and einsum cost ~0.12 ms
    # per update (session 19). An empty ``crease`` / ``plane_normals`` switches that class off; the tests and the sums
    # are numpy's (einsum over three terms, :func:`_grazing_mask`'s cosine), so the leads are the same.
    with_crease = crease.shape[0] > 0
    with_grazing = max_cos > 0 and plane_normals.shape[0] > 0
    for r in range(used.size):
        i = used[r]
        a, b = on_lead, off_lead
        if with_crease:
            if crease[i]:
                a, b = crease_on, crease_off
            else:
                d0, d1, d2 = centre[0] - points[i, 0], centre[1] - points[i, 1], centre[2] - points[i, 2]
                if edge_normals[i, 0] * d0 + edge_normals[i, 1] * d1 + edge_normals[i, 2] * d2 > 0:
                    b = beyond_off
        if with_grazing:
            n0, n1, n2 = plane_normals[i, 0], plane_normals[i, 1], plane_normals[i, 2]
            if n0 * n0 + n1 * n1 + n2 * n2 > 0.25:
                d0, d1, d2 = points[i, 0] - centre[0], points[i, 1] - centre[1], points[i, 2] - centre[2]
                cos = abs(n0 * d0 + n1 * d1 + n2 * d2) / max(np.sqrt(d0 * d0 + d1 * d1 + d2 * d2), 1e-12)
                if cos < max_cos:
                    a, b = grazing_on, grazing_off
        on[r] = a
        off[r] = b


def point_leads(used: np.ndarray, crease: np.ndarray | None, edge_normals: np.ndarray, points: np.ndarray,
                plane_normals: np.ndarray | None, camera_centre: np.ndarray, config) -> tuple[np.ndarray, np.ndarray]:
    """(ON, OFF) lead in pixels of each map point ``used`` (indices into the whole map's ``points`` (N, 3) world metres,
    ``edge_normals`` (N, 3) their unit edge normals, ``plane_normals`` (N, 3) their surfaces' or None, ``crease`` (N,)
    bool of :func:`crease_points` or None) by an :class:`~evpose.tracker.event_registration_config.EventRegistrationConfig`:
    its plain ``on_lead_px`` / ``off_lead_px``; on a crease the ``crease_*`` leads; elsewhere, with ``crease`` given,
    ``beyond_off_lead_px`` where the camera centre (``camera_centre``, world) lies on the edge normal's side; grazing
    points (``grazing_max_cos``, see :func:`grazing_points`) the ``grazing_*`` leads, whatever their class."""
    c = config
    used = np.ascontiguousarray(used, dtype=np.int64)
    on, off = np.empty(used.size), np.empty(used.size)
    _point_leads(used, _NO_MASK if crease is None else crease, edge_normals, points,
                 _NO_NORMALS if plane_normals is None else _floats(plane_normals), np.asarray(camera_centre, dtype=np.float64),
                 float(c.on_lead_px), float(c.off_lead_px), float(c.crease_on_lead_px), float(c.crease_off_lead_px),
                 float(c.beyond_off_lead_px), float(c.grazing_max_cos), float(c.grazing_on_lead_px), float(c.grazing_off_lead_px),
                 on, off)
    return on, off


_NO_MASK = np.zeros(0, np.bool_)
_NO_NORMALS = np.zeros((0, 3))


def _floats(a) -> np.ndarray:
    # The map keeps its normals as float32: converting the whole map per call would cost more than the gather it
    # replaces, and the kernel promotes them as numpy did.
    a = np.asarray(a)
    return a if a.dtype.kind == "f" else a.astype(np.float64)


def grazing_points(plane_normals: np.ndarray, points: np.ndarray, camera_centre: np.ndarray, max_cos: float,
                   used: np.ndarray | None = None) -> np.ndarray:
    """(M,) bool: the points (``points`` (M, 3) world, metres, ``plane_normals`` (M, 3) their surfaces' unit normals,
    zero = unknown) whose normal makes an absolute cosine below ``max_cos`` with the ray from ``camera_centre``
    (world, metres); points without a normal never are. With ``used`` (M,) indices, both arrays are the whole map's
    and the answer is for the rows ``used``."""
    n, p = _floats(plane_normals), _floats(points)
    rows = np.arange(len(n), dtype=np.int64) if used is None else np.asarray(used, dtype=np.int64)
    return _grazing_mask(n, rows, p, rows, np.asarray(camera_centre, dtype=np.float64), float(max_cos))


def add_grazing_off_trail(trail: np.ndarray, polarity: np.ndarray, plane_normals: np.ndarray, used: np.ndarray,
                          points: np.ndarray, camera_centre: np.ndarray, config) -> None:
    """Adds a :class:`~evpose.tracker.config.TrackerConfig`'s ``registration.fused_grazing_off_trail_px`` to the field
    ``trail`` (pixels, as ``used``) of the map points ``used`` (``points`` their positions, ``plane_normals`` the
    whole map's) predicted to fire OFF events (``polarity`` < 0) whose surface is grazing by
    ``event_registration.grazing_max_cos``, seen from ``camera_centre``; nothing when either is 0."""
    extra, max_cos = float(config.registration.fused_grazing_off_trail_px), float(config.event_registration.grazing_max_cos)
    if extra == 0 or not max_cos > 0 or not len(used):
        return
    used = np.asarray(used, dtype=np.int64)
    graze = _grazing_mask(_floats(plane_normals), used, _floats(points),
                          np.arange(used.size, dtype=np.int64), np.asarray(camera_centre, dtype=np.float64), max_cos)
    trail[(np.asarray(polarity) < 0) & graze] += extra


def crease_points(points: np.ndarray, plane_normals: np.ndarray, region_id: np.ndarray, radius: float,
                  max_cos: float = 0.5) -> np.ndarray:
    """(N,) bool: the map points (``points`` (N, 3) world, metres) on a crease: a point of another region
    (``region_id`` (N,), -1 = none) lies within ``radius`` (metres) and the two surfaces' unit normals
    (``plane_normals`` (N, 3), zero = unknown) make an absolute cosine below ``max_cos``. All False when ``radius`` <= 0."""
    n = len(points)
    out = np.zeros(n, np.bool_)
    if not float(radius) > 0 or n == 0:
        return out
    pn = np.asarray(plane_normals, dtype=np.float64)
    reg = np.asarray(region_id)
    pairs = cKDTree(np.asarray(points, dtype=np.float64)).query_pairs(float(radius), output_type="ndarray")
    if not len(pairs):
        return out
    i, j = pairs[:, 0], pairs[:, 1]
    known = (np.einsum("ij,ij->i", pn[i], pn[i]) > 0.25) & (np.einsum("ij,ij->i", pn[j], pn[j]) > 0.25)
    hit = known & (reg[i] != reg[j]) & (reg[i] >= 0) & (reg[j] >= 0) & (np.abs(np.einsum("ij,ij->i", pn[i], pn[j])) < float(max_cos))
    out[i[hit]] = True
    out[j[hit]] = True
    return out


def add_crease_off_trail(trail: np.ndarray, polarity: np.ndarray, crease: np.ndarray | None, plane_normals: np.ndarray,
                         used: np.ndarray, points: np.ndarray, camera_centre: np.ndarray, config) -> None:
    """Moves the field ``trail`` (pixels, as ``used``) of the face-on map points ``used`` predicted to fire OFF events
    (``polarity`` < 0) by half a :class:`~evpose.tracker.config.TrackerConfig`'s
    ``registration.fused_crease_off_trail_px``: further behind on a crease (``crease``, the whole map's mask of
    :func:`crease_points`), less elsewhere; grazing points (``event_registration.grazing_max_cos``, seen from
    ``camera_centre``; ``points`` the used points' positions) are left as they are. Nothing when ``crease`` is None or
    the setting 0."""
    half = 0.5 * float(config.registration.fused_crease_off_trail_px)
    if crease is None or half == 0 or not len(used):
        return
    off = np.asarray(polarity) < 0
    max_cos = float(config.event_registration.grazing_max_cos)
    if max_cos > 0:
        off &= ~grazing_points(np.asarray(plane_normals)[used], points, camera_centre, max_cos)
    trail[off] += np.where(np.asarray(crease)[used][off], half, -half)
