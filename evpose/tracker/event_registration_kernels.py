"""The compiled per-event kernels of :mod:`evpose.tracker.event_registration`: the events' association with their
nearest points, their robust normal equations at one pose, and the gauge-free per-point offsets.

Not kept (session 13, seed 0 at 346x260, the 393 updates' inputs, kernels timed alternated, the same outputs bit for
bit): :func:`_linearise_events` with its normal equations summed in 42 scalars instead of ``H`` / ``b`` (40.7 -> 38.6
us per pass, not worth 50 lines), or with the gate, the Huber weight and the polarity lead as selects and gated
events summed with weight 0 (40.7 -> 43.1 us, slower: the kernel does not wait on branches); the association with
cells of one radius (3 x 3 cells: 87.7 -> 84.7 us), with its points counting-sorted by cell (contiguous cell lists,
75.4 us against 76.5 for the linked lists, both with the selects kept): ~2.6 candidates per event, the time goes
elsewhere (the event loop ~60 us cold against ~20 us called again and again on one update's inputs)."""

from __future__ import annotations

import numba as nb
import numpy as np

from evpose.tracker.camera_point import camera_point
from evpose.tracker.offset_fit import add_offset_row, apply_offset_fit, normal_px_per_m
from evpose.tracker.registration_kernels import _projected_normal, _rho_weight


@nb.njit(cache=True)
def _kept_events(keep, x, y, t, p, table, ex, ey, et, ep):
    """The kept events (``keep``) in order into ``ex``, ``ey`` (float64 pixels; through the (H, W, 2) undistortion
    ``table`` unless it is empty), ``et``, ``ep``; returns how many (one pass instead of a flatnonzero, four gathers
    and four conversions)."""
    n = 0
    undistort = table.shape[0] > 0
    for i in range(keep.shape[0]):
        if not keep[i]:
            continue
        if undistort:
            ex[n] = np.float64(table[y[i], x[i], 0])
            ey[n] = np.float64(table[y[i], x[i], 1])
        else:
            ex[n] = np.float64(x[i])
            ey[n] = np.float64(y[i])
        et[n] = t[i]
        ep[n] = p[i]
        n += 1
    return n


NO_EVENT = np.iinfo(np.int64).min
"""A pixel without an event yet, in :func:`_pixel_gaps`'s ``last``."""


@nb.njit(cache=True)
def _pixel_gaps(keep, x, y, t, p, width, last, gaps):
    """For each kept event (``keep``), in order, the time since its pixel's previous event of the same polarity into
    ``gaps`` (us; 2**62 when none), ``last`` ((2 W H,) int64, ``NO_EVENT`` = none) the pixels' latest event times,
    which every event of the step (kept or not) updates; returns how many kept."""
    n = 0
    for i in range(keep.shape[0]):
        j = (np.int64(y[i]) * width + np.int64(x[i])) * 2 + (1 if p[i] > 0 else 0)
        prev = last[j]
        if keep[i]:
            gaps[n] = t[i] - prev if prev != NO_EVENT else np.int64(2) ** 62
            n += 1
        last[j] = t[i]
    return n


@nb.njit(cache=True)
def _associate_nearest(points, tangents, used, R_cw, t_cw, fx, fy, cx, cy, radius, width, height, n_events, ex, ey, et, ep,
                       eg, polarity, pts, tg, assoc):
    """Gathers the rows ``used`` of ``points`` / ``tangents`` into ``pts`` / ``tg`` and associates each of the first
    ``n_events`` events with the point (row of ``pts``) projected nearest to its (rounded) pixel within ``radius``
    (ties: the lower index) if that point may fire the event's polarity; the associated events are moved to the
    front of ``ex``, ``ey``, ``et``, ``ep`` (and ``eg``, the gaps of :func:`_pixel_gaps`) in their order, their points in ``assoc``. Returns how many. The points
    are bucketed in cells of ``2 radius`` pixels, so each event looks at a few points only. (Marking every pixel of
    an image-sized grid with its nearest point, as :mod:`evpose.fusion.aligned_surface` marks its patches, gave the
    same associations bit for bit at the same CPU cost in a run, ~0.06 ms when hot, with three image-sized arrays to
    keep.)"""
    m = used.shape[0]
    for j in range(m):
        i = used[j]
        for c in range(3):
            pts[j, c] = points[i, c]
            tg[j, c] = tangents[i, c]
    cell = max(2.0 * radius, 1.0)
    nc = int(np.ceil((width + 2.0 * radius + 2.0) / cell)) + 1
    nr = int(np.ceil((height + 2.0 * radius + 2.0) / cell)) + 1
    head = np.full(nc * nr, -1, np.int64)
    nxt = np.empty(m, np.int64)
    pu = np.empty(m)
    pv = np.empty(m)
    for k in range(m - 1, -1, -1):  # lists in ascending point order
        X, Y, Z = camera_point(pts, k, R_cw, t_cw)
        if not (Z > 1e-6):
            continue
        u = fx * X / Z + cx
        v = fy * Y / Z + cy
        if not (u > -radius - 1 and u < width + radius and v > -radius - 1 and v < height + radius):
            continue
        pu[k] = u
        pv[k] = v
        c = int((u + radius + 1.0) / cell)
        r = int((v + radius + 1.0) / cell)
        nxt[k] = head[r * nc + c]
        head[r * nc + c] = k
    r2 = radius * radius
    n = 0
    for i in range(n_events):
        xx = int(np.floor(ex[i] + 0.5))
        yy = int(np.floor(ey[i] + 0.5))
        if yy < 0 or yy >= height or xx < 0 or xx >= width:
            continue
        best = np.float32(np.inf)
        bk = -1
        c0 = max(int((xx - radius + radius + 1.0) / cell), 0)
        c1 = min(int((xx + radius + radius + 1.0) / cell), nc - 1)
        r0 = max(int((yy - radius + radius + 1.0) / cell), 0)
        r1 = min(int((yy + radius + radius + 1.0) / cell), nr - 1)
        for rr in range(r0, r1 + 1):
            for cc in range(c0, c1 + 1):
                k = head[rr * nc + cc]
                while k >= 0:
                    dx = xx - pu[k]
                    dy = yy - pv[k]
                    d = np.float32(dx * dx + dy * dy)
                    # Selects, not branches: whether a candidate wins is unpredictable (~12 % less time in a run).
                    take = (d <= r2) & ((d < best) | ((d == best) & (k < bk)))
                    best = d if take else best
                    bk = k if take else bk
                    k = nxt[k]
        if bk < 0:
            continue
        if polarity.shape[0] and polarity[bk] != 0 and polarity[bk] != ep[i]:
            continue
        ex[n] = ex[i]  # n <= i: in place
        ey[n] = ey[i]
        et[n] = et[i]
        ep[n] = ep[i]
        eg[n] = eg[i]
        assoc[n] = bk
        n += 1
    return n


@nb.njit(cache=True)
def _linearise_events(n_events, ex, ey, et, ep, assoc, points, tangents, R_cw, t_cw, fx, fy, cx, cy, twist, t_ref, on_lead, off_lead,
                      eg, burst, huber, gate, H, b, sw, swr, swj, pscale):
    """Robust normal equations of the first ``n_events`` events' distances to their points' edge lines (event ``i``'s
    point the row ``assoc[i]`` of ``points`` / ``tangents``), each point projected at its
    event's time (the pose ``t_ref - t`` earlier along ``twist``, body frame, rotation then translation, per
    second). An ON event of row ``k``'s point is taken ``on_lead[k]`` pixels ahead of the edge along its motion, an OFF
    event ``off_lead[k]`` (see ``EventRegistrationConfig.on_lead_px`` and ``grazing_max_cos``); with ``burst[0]`` > 0 an
    event whose pixel fired the same polarity ``eg[i]`` us before, less than ``burst[0]`` of the edge's pixel-crossing
    times (1 / its normal speed) ago, adds ``burst[2]`` (ON) / ``burst[4]`` (OFF) to that lead, any other ``burst[1]`` /
    ``burst[3]`` (see ``EventRegistrationConfig.follower_crossings``). With 8 entries (``burst[0]`` may then be 0) an
    ON / OFF event's lead also falls by ``burst[5]`` / ``burst[6]`` seconds times how much its edge's normal image
    speed exceeds ``burst[7]`` pixels per second (:mod:`evpose.tracker.event_lag`). ``sw`` / ``swr`` (M,) get each
    point's sums of the robust weights and weighted residuals, ``swj`` (M, 6) of the weighted Jacobians when it has
    M rows (else it is left alone; :mod:`evpose.tracker.edge_clusters`), and each robust weight is multiplied by its
    point's ``pscale`` when that has M entries. Returns (cost, events used, sum of w r^2)."""
    with_j = swj.shape[0] == sw.shape[0]
    with_scale = pscale.shape[0] == sw.shape[0]
    for k in range(sw.shape[0]):
        sw[k] = 0.0
        swr[k] = 0.0
        if with_j:
            for a in range(6):
                swj[k, a] = 0.0
    for r in range(6):
        b[r] = 0.0
        for c in range(6):
            H[r, c] = 0.0
    cost = 0.0
    used = 0
    swr2 = 0.0
    J = np.zeros(6)
    with_burst = burst.shape[0] >= 5 and burst[0] > 0.0
    with_lag = burst.shape[0] == 8 and (burst[5] != 0.0 or burst[6] != 0.0)
    wx, wy, wz, vx, vy, vz = twist[0], twist[1], twist[2], twist[3], twist[4], twist[5]
    for i in range(n_events):
        k = assoc[i]
        X, Y, Z = camera_point(points, k, R_cw, t_cw)
        dt = (t_ref - et[i]) * 1e-6
        # T_e = T Exp(-twist dt): X_e = X + dt (w x X) + dt v to first order.
        Xe = X + dt * (wy * Z - wz * Y + vx)
        Ye = Y + dt * (wz * X - wx * Z + vy)
        Ze = Z + dt * (wx * Y - wy * X + vz)
        if not (Ze > 1e-6):
            continue
        iz = 1.0 / Ze
        u = fx * Xe * iz + cx
        v = fy * Ye * iz + cy
        nu, nv = _projected_normal(tangents, k, R_cw, Xe, Ye, Ze, fx, fy)
        if nu == 0.0 and nv == 0.0:
            continue
        pux = fx * iz
        puz = -fx * Xe * iz * iz
        pvy = fy * iz
        pvz = -fy * Ye * iz * iz
        # d res / d xi = -(n . d(u, v) / d xi), right perturbation (as registration's rows).
        J[0] = -(nu * (-puz * Ye) + nv * (pvy * Ze - pvz * Ye))
        J[1] = -(nu * (puz * Xe - pux * Ze) + nv * (pvz * Xe))
        J[2] = -(nu * (pux * Ye) + nv * (-pvy * Xe))
        J[3] = -(nu * (-pux))
        J[4] = -(nv * (-pvy))
        J[5] = -(nu * (-puz) + nv * (-pvz))
        res = nu * (ex[i] - u) + nv * (ey[i] - v)
        lead = on_lead[k] if ep[i] > 0 else off_lead[k]
        if lead != 0.0 or with_burst or with_lag:
            vn = 0.0  # the edge's image speed along n: -J . twist
            for a in range(6):
                vn -= J[a] * twist[a]
            if with_lag:
                # A pixel's threshold crossing fires late by a time, so its event trails the edge by that time
                # times the edge's speed, about the reference speed at which the class leads were measured.
                lead -= (burst[5] if ep[i] > 0 else burst[6]) * (abs(vn) - burst[7])
            if with_burst and vn != 0.0:
                # The pixel's previous same-polarity event less than burst[0] crossing times ago: the same edge's
                # passage, whose later events trail its first (the threshold crossings of a pixel-integrated edge).
                follower = eg[i] * abs(vn) * 1e-6 < burst[0]
                if ep[i] > 0:
                    lead += burst[2] if follower else burst[1]
                else:
                    lead += burst[4] if follower else burst[3]
            if vn > 0.0:
                res -= lead
            elif vn < 0.0:
                res += lead
        if abs(res) > gate:
            continue
        rho, w = _rho_weight(res, 1, huber)
        if with_scale:
            rho *= pscale[k]
            w *= pscale[k]
        sw[k] += w
        swr[k] += w * res
        cost += rho
        used += 1
        swr2 += w * res * res
        if with_j:
            for a in range(6):
                swj[k, a] += w * J[a]
        for a in range(6):
            b[a] += w * res * J[a]
            for c in range(6):
                H[a, c] += w * J[a] * J[c]
    return cost, used, swr2


@nb.njit(cache=True)
def _learn_offsets(idx, sw, swr, min_weight, points, base, normals, tangents, offsets, R_cw, t_cw, fx, fy, cx, cy,
                   gain, clip_px, max_offset, min_pxm, fit_out):
    """Gauge-free per-point offsets from the events: each point ``idx[j]`` (rows of the full-map arrays) with robust
    weight ``sw[j]`` >= ``min_weight`` observes its events' mean distance ``swr[j] / sw[j]`` (pixels along its image
    normal); the 6-DoF pose change that best explains these is fitted (``fit_out``) and ``gain`` of what it leaves
    is added to ``offsets`` (metres along ``normals``) and written into ``points``. Returns how many moved."""
    m = idx.shape[0]
    H = np.zeros((6, 6))
    b = np.zeros(6)
    jac = np.zeros((m, 6))
    obs = np.zeros(m)
    pxm = np.zeros(m)
    ok = np.zeros(m, np.bool_)
    n_ok = 0
    for r in range(6):
        fit_out[r] = np.nan
    for j in range(m):
        i = idx[j]
        if sw[j] < min_weight:
            continue
        o = swr[j] / sw[j]
        if abs(o) > clip_px:
            continue
        X, Y, Z = camera_point(points, i, R_cw, t_cw)
        if Z <= 1e-6:
            continue
        iz = 1.0 / Z
        nu, nv = _projected_normal(tangents, i, R_cw, X, Y, Z, fx, fy)
        if nu == 0.0 and nv == 0.0:
            continue
        p = normal_px_per_m(normals, i, R_cw, X, Y, Z, iz, nu, nv, fx, fy)
        if abs(p) < min_pxm:
            continue
        pux = fx * iz
        puz = -fx * X * iz * iz
        pvy = fy * iz
        pvz = -fy * Y * iz * iz
        add_offset_row(H, b, jac, j, o, nu, nv, X, Y, Z, pux, puz, pvy, pvz)
        obs[j] = o
        pxm[j] = p
        ok[j] = True
        n_ok += 1
    return apply_offset_fit(H, b, n_ok, ok, idx, obs, pxm, jac, offsets, points, base, normals, False, gain, max_offset, fit_out)
