"""The numba kernels of :class:`~evpose.fusion.aligned_surface.AlignedTimeSurface` (``T_align``).

Marking the used map points' patches (nearest point per pixel, generation tags), picking each patch pixel's time from
the SP-TS's last-timestamp maps, and judging / classifying events against the patches. The module docstring of
:mod:`evpose.fusion.aligned_surface` says what they compose and gives their timings.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from evpose.frontend.noise_filter import NEVER_US
from evpose.fusion.cache_prefetch import prefetch_read, prefetch_write

PREFETCH_AHEAD = 16
"""How many patch pixels (events) ahead the selecting (judging) kernels prefetch the maps they read there."""
MARK_AHEAD = 4
"""How many points ahead :func:`_mark_patches` prefetches the rows of a point's patch."""


@nb.njit(cache=True)
def _reset_touched(touched, n, last):
    """Put the composed map back to NEVER at the pixels the previous step wrote (cheaper than clearing the box).

    ``accept`` / ``dist2`` / ``owner`` need no reset: their pixels count only when tagged with the current
    generation (see :class:`AlignedTimeSurface`), which saves three of the four scattered writes per pixel.
    """
    for i in range(n):
        last[touched[i, 0], touched[i, 1]] = NEVER_US


@nb.njit(cache=True)
def _mark_patches(points, R_cw, t_cw, fx, fy, cx, cy, polarity, radius, box, gen, tag, dist2, owner, touched):
    """Each pixel within ``radius`` of a projected point takes the polarity its *nearest* point accepts (1 ON, 2 OFF,
    3 both) in ``tag`` = ``gen * 4 + polarity``; a pixel whose tag is of another generation is in no patch (its
    ``dist2`` / ``owner`` are stale). Returns how many pixels it wrote, listed in ``touched``.

    Nearest, not any: patches of neighbouring contours overlap, and a union would
    read the combined surface wherever an ON and an OFF contour are within two
    radii, which undoes the filter (measured: the union at 12 px scored exactly
    like no polarity filter).
    """
    r0, r1, c0, c1 = box[0], box[1], box[2], box[3]
    n = 0
    rad = int(np.ceil(radius))
    r2 = radius * radius
    # Flat views with unsigned offsets (no negative-index wrap per access), each pixel's tag read once, and the
    # squared column offsets of a point computed once for its rows: the same values (``dx * dx + dy * dy``, the same
    # products and sum) and the same writes in the same order, ~15 % less time (session 12).
    width = tag.shape[1]
    tag_flat = tag.reshape(-1)
    dist2_flat = dist2.reshape(-1)
    owner_flat = owner.reshape(-1)
    gen_bits = np.uint16(gen << 2)
    dxx = np.empty(2 * rad + 1)
    # Projections first, so the patch rows of the point MARK_AHEAD on are prefetched while this one is marked.
    m = points.shape[0]
    us = np.empty(m)
    vs = np.empty(m)
    in_box = np.zeros(m, np.bool_)
    for k in range(m):
        X = R_cw[0, 0] * points[k, 0] + R_cw[0, 1] * points[k, 1] + R_cw[0, 2] * points[k, 2] + t_cw[0]
        Y = R_cw[1, 0] * points[k, 0] + R_cw[1, 1] * points[k, 1] + R_cw[1, 2] * points[k, 2] + t_cw[1]
        Z = R_cw[2, 0] * points[k, 0] + R_cw[2, 1] * points[k, 1] + R_cw[2, 2] * points[k, 2] + t_cw[2]
        if not (Z > 1e-6):
            continue
        u = fx * X / Z + cx
        v = fy * Y / Z + cy
        if u > c0 - radius - 1 and u < c1 + radius and v > r0 - radius - 1 and v < r1 + radius:
            us[k], vs[k], in_box[k] = u, v, True
    for k in range(m):
        ahead = k + MARK_AHEAD
        if ahead < m and in_box[ahead]:
            x0 = min(max(int(np.floor(us[ahead] + 0.5)) - rad, c0), width - 1)
            cv = int(np.floor(vs[ahead] + 0.5))
            for yy in range(max(cv - rad, r0), min(cv + rad + 1, r1)):
                q = yy * width + x0
                prefetch_write(tag_flat, q)
                prefetch_write(dist2_flat, q)
                prefetch_write(owner_flat, q)
        if not in_box[k]:
            continue
        u = us[k]
        v = vs[k]
        flag = np.uint16(1) if polarity[k] > 0 else (np.uint16(2) if polarity[k] < 0 else np.uint16(3))
        new_tag = np.uint16(gen_bits | flag)
        cu = int(np.floor(u + 0.5))
        cv = int(np.floor(v + 0.5))
        x0 = max(cu - rad, c0)
        x1 = min(cu + rad + 1, c1)
        for xx in range(x0, x1):
            dx = xx - u
            dxx[xx - x0] = dx * dx
        for yy in range(max(cv - rad, r0), min(cv + rad + 1, r1)):
            dy = yy - v
            dyy = dy * dy
            row = np.uint64(yy * width)
            for xx in range(x0, x1):
                d = np.float32(dxx[xx - x0] + dyy)
                if d <= r2:
                    p = row + np.uint64(xx)
                    t = tag_flat[p]
                    if (t >> 2) != gen:  # first patch on this pixel in this step: it was empty
                        touched[n, 0] = yy
                        touched[n, 1] = xx
                        n += 1
                        dist2_flat[p] = d
                        tag_flat[p] = new_tag
                        owner_flat[p] = k
                    else:
                        before = dist2_flat[p]
                        if d < before:
                            dist2_flat[p] = d
                            tag_flat[p] = new_tag
                            owner_flat[p] = k
                        elif d == before:
                            tag_flat[p] = t | flag  # equidistant points of both polarities: keep both
    return n


@nb.njit(cache=True)
def _flat_views(tag, owner, last_on, last_off, last_comb):
    """(row width as uint64, then flat views of the five maps) for the selecting kernels' one-offset pixel reads."""
    return (np.uint64(tag.shape[1]), tag.reshape(-1), owner.reshape(-1), last_on.reshape(-1), last_off.reshape(-1),
            last_comb.reshape(-1))


@nb.njit(cache=True, inline="always")
def _prefetch_maps(touched, j, n, width, on_flat, off_flat, comb_flat):
    """Prefetch the three SP-TS maps at patch pixel ``j`` (when ``j < n``): the selecting passes read them there
    ``PREFETCH_AHEAD`` pixels later. The patch pixels come in marking order, scattered over the maps' rows, and the maps
    are out of cache by then (0.7 MB each at 346x260)."""
    if j < n:
        q = np.uint64(touched[j, 0]) * width + np.uint64(touched[j, 1])
        prefetch_read(on_flat, q)
        prefetch_read(off_flat, q)
        prefetch_read(comb_flat, q)


@nb.njit(cache=True)
def _select_times(touched, n, tag, owner, last_on, last_off, last_comb, recent_us, times, has_events):
    """``times[i]``: the last timestamp the accepted polarity of patch pixel ``touched[i]`` selects (every other
    pixel reads NEVER); ``has_events[k]`` is set when a pixel point ``k`` owns holds an accepted event at or after
    ``recent_us``. A compact list, not an image: the distance field reads it directly
    (:mod:`evpose.fusion.aligned_field`), and :meth:`AlignedTimeSurface.last_of` scatters it only when asked."""
    # Flat views and one unsigned offset per pixel (no 2-D index arithmetic with negative-index wrap per array read):
    # the same reads, ~45 % less time with the maps out of cache (session 12, 20 demo steps: 320-350 -> 175 us).
    width, tag_flat, owner_flat, on_flat, off_flat, comb_flat = _flat_views(tag, owner, last_on, last_off, last_comb)
    for i in range(n):
        _prefetch_maps(touched, i + PREFETCH_AHEAD, n, width, on_flat, off_flat, comb_flat)
        p = np.uint64(touched[i, 0]) * width + np.uint64(touched[i, 1])
        a = tag_flat[p] & 3
        if a == 1:
            t = on_flat[p]
        elif a == 2:
            t = off_flat[p]
        else:
            t = comb_flat[p]
        times[i] = t
        if t >= recent_us:
            has_events[owner_flat[p]] = True


@nb.njit(cache=True)
def _select_times_reopening(touched, n, tag, owner, last_on, last_off, last_comb, recent_us, times, has_events, polarity,
                            seen_other):
    """:func:`_select_times`, then patches of single-polarity points that show no recent event of their polarity but do
    of the other accept both: their prediction is contradicted by the events themselves (a wrong sign or edge normal),
    and reading only the predicted polarity would hide their own edge. Updates ``tag`` / ``times`` / ``has_events`` /
    ``polarity`` in place; returns how many points it reopened. ``seen_other`` (M,) is scratch (all False on entry).

    The other polarity is looked at in the selecting pass (flat views, as there), not in a second pass over the
    patch pixels: the same outputs, without reading every patch pixel's tag and owner twice (the second pass cost
    ~0.15 ms per update in ``stpe+filter`` at 346x260, session 14)."""
    width, tag_flat, owner_flat, on_flat, off_flat, comb_flat = _flat_views(tag, owner, last_on, last_off, last_comb)
    for i in range(n):
        _prefetch_maps(touched, i + PREFETCH_AHEAD, n, width, on_flat, off_flat, comb_flat)
        p = np.uint64(touched[i, 0]) * width + np.uint64(touched[i, 1])
        a = tag_flat[p] & 3
        k = owner_flat[p]
        if a == 1:
            t = on_flat[p]
            if off_flat[p] >= recent_us:
                seen_other[k] = True
        elif a == 2:
            t = off_flat[p]
            if on_flat[p] >= recent_us:
                seen_other[k] = True
        else:
            t = comb_flat[p]
        times[i] = t
        if t >= recent_us:
            has_events[k] = True
    reopened = 0
    for k in range(polarity.shape[0]):
        if seen_other[k] and not has_events[k] and polarity[k] != 0:
            polarity[k] = 0
            has_events[k] = True
            reopened += 1
        else:
            seen_other[k] = False
    if reopened:
        for i in range(n):
            p = np.uint64(touched[i, 0]) * width + np.uint64(touched[i, 1])
            if seen_other[owner_flat[p]]:
                tag_flat[p] |= 3
                times[i] = comb_flat[p]
    return reopened


@nb.njit(cache=True)
def _scatter_times(touched, n, times, out):
    """``out`` at the patch pixels: their selected timestamps (the rest of ``out`` already reads NEVER)."""
    for i in range(n):
        out[touched[i, 0], touched[i, 1]] = times[i]


@nb.njit(cache=True)
def _judge_events(x, y, p, keep, width, lut, gen, tag, owner, dist2, box, polarity, r2, out_label, out_point, out_majority):
    """One pass over a step's events: the counts of the filter (events judged, outside every patch, of the wrong
    polarity inside a patch) and, for the kept events in order, the labels and owning points :func:`_classify_owned`
    gives within ``sqrt(r2)`` (``out_*`` hold one entry per kept event). One pass instead of two over the events
    (profiled in ``full`` at 346x260: the two passes were about a third of the filter's kernel time).
    ``out_majority`` (M,): per point the sign of the summed polarities of its events, as
    :func:`~evpose.fusion.event_labels.observed_point_polarity` gives it from ``out_point`` (sign learning then
    needs neither the kept events' copy nor another pass)."""
    score = np.zeros(out_majority.shape[0], np.int64)
    n = 0
    outside = 0
    wrong = 0
    height = tag.shape[0]
    tag_flat = tag.reshape(-1)  # flat views: one offset per pixel, as in _select_times
    owner_flat = owner.reshape(-1)
    dist2_flat = dist2.reshape(-1)
    m = 0
    n_ev = x.shape[0]
    for i in range(n_ev):
        ahead = i + PREFETCH_AHEAD
        if ahead < n_ev:  # the grid at an event's pixel, fetched ahead: the events come in time order, scattered
            q = np.int64(y[ahead]) * width + np.int64(x[ahead])
            if lut.shape[0]:
                q = lut[q]
            if 0 <= q < tag_flat.shape[0]:
                prefetch_read(tag_flat, q)
                prefetch_read(owner_flat, q)
                prefetch_read(dist2_flat, q)
        if not keep[i]:
            continue
        out_label[m] = -1
        out_point[m] = -1
        m += 1
        j = lut[np.int64(y[i]) * width + np.int64(x[i])] if lut.shape[0] else np.int64(y[i]) * width + np.int64(x[i])
        if j < 0:
            continue
        n += 1
        r = j // width
        c = j - r * width
        q = np.uint64(j)  # the pixel's offset in the flat views (``j`` is row * width + column)
        if not (box[0] <= r < box[1] and box[2] <= c < box[3] and r < height and (tag_flat[q] >> 2) == gen):
            outside += 1
            continue
        a = tag_flat[q] & 3
        if (a == 1 and p[i] < 0) or (a == 2 and p[i] > 0):
            wrong += 1
        k = owner_flat[q]
        if k >= 0 and dist2_flat[q] <= r2:
            out_point[m - 1] = k
            out_label[m - 1] = 1 if (polarity[k] == 0 or polarity[k] == p[i]) else 0
            score[k] += p[i]
    for k in range(out_majority.shape[0]):
        out_majority[k] = 1 if score[k] > 0 else (-1 if score[k] < 0 else 0)
    return n, outside, wrong


@nb.njit(cache=True)
def _classify_owned(x, y, p, width, lut, gen, tag, owner, dist2, box, polarity, r2, out_label, out_point):
    """Label events by the patch owner of their (ideal) pixel if it lies within ``sqrt(r2)`` of it: as
    :func:`~evpose.fusion.polarity.classify_events`, on the grid :meth:`AlignedTimeSurface.compose` built."""
    for i in range(x.shape[0]):
        out_label[i] = -1
        out_point[i] = -1
        j = lut[np.int64(y[i]) * width + np.int64(x[i])] if lut.shape[0] else np.int64(y[i]) * width + np.int64(x[i])
        if j < 0:
            continue
        r = j // width
        c = j - r * width
        if not (box[0] <= r < box[1] and box[2] <= c < box[3]):
            continue
        if (tag[r, c] >> 2) != gen:
            continue
        k = owner[r, c]
        if k < 0 or dist2[r, c] > r2:
            continue
        out_point[i] = k
        out_label[i] = 1 if (polarity[k] == 0 or polarity[k] == p[i]) else 0
