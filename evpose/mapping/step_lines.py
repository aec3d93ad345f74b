"""A low step's edge as one line per straight run: fitted to all of the step face's points along the run.

A landing pad 15 cm high on a sparse scan has no region on its sides, so its rims are placed by
:func:`evpose.mapping.adjacency.snap_to_steps`: each contour point moves to the median of the one to three
face points nearest to it. Those few points carry the scan's range noise (5 mm, along the face's normal:
across the edge), and as the contour passes from one set of them to the next the rim jumps: on the
simulated landing the pad's four top rims and four feet came out as 10-40 cm pieces a few millimetres
off and tilted against each other (p10 / p90 of the error along the edge normal about -5 / +6 mm; the pad's
rim is most of what the final approach sees). The rim is straight: one line fitted to every face point
along a straight run of the contour (some 30-45 on a 3 m side at 100 points/m^2) places it within a
millimetre or two.

Runs are the straight pieces :func:`evpose.mapping.contours.straighten` gave one common normal; a run's
face points are those :func:`snap_to_steps` reads (not of its own region nor of a region parallel to it,
off its plane by more than ``min_offset`` and at most ``max_offset``), within ``max_shift`` across the run's
line and along its extent. A robust (trimmed) least-squares line ``across = a + b * along`` through them
replaces the run's points (kept on their own plane) and its tilt turns their normal. Runs with too few
face points, or whose face points do not span enough of the run to fix a tilt, keep a constant offset
(the face points' median) or stay as they are.

Measured (session 30, scripts in ``/tmp/s30/map30/``; error = distance along the point's edge normal to the nearest true
edge, points within 3 cm of one, 2 s landing clouds, points within 4 m of the pad's centre): the pad's and crates' feet
2.90 -> 2.05 mm RMS and tops 3.87 -> 3.01 mm (seeds 0-1, ``buildcmp.py``; share > 5 mm off 9.5 / 10.5 -> 3.7 / 3.9 %);
seed 0's pad top rim at y = -1.5 m, traced 7 degrees tilted from a notch, 71.7 -> 0.6 mm RMS (the fit needs the second
gather about its own line and a slope of up to 0.25, ``segcmp.py``). Tracking (``full``, 2 s landing from ground truth,
``run.py``, mean ATE of seeds 0-11): 346x260 4.621 -> 4.471 mm (paired -0.149 +- 0.140, 7 of 12 seeds better; 0-3 5.335
-> 4.950), 240x180 5.438 -> 5.313 mm (-0.125 +- 0.157, 6 of 12; seed 0 7.78 -> 6.22). Bundled demos (``evpose track
demo_data/X.h5`` on ``maps/landing_map.ply`` rebuilt, ``evpose eval --align none``): ``landing`` / ``landing_fast`` /
``landing_dynamic`` 7.12 / 9.98 / 5.90 -> 7.24 / 9.53 / 4.97 mm (``demos.sh``). Contour-map precision / recall /
recall_faces (``evpose.bench.mapping`` figures, simulator clouds of seeds 0-1 and the bundled cloud, ``prscore.py``):
landing 99.41 / 96.74 / 96.85 -> 99.46 / 96.80 / 96.90 %, indoor 97.16 / 90.55 / 91.53 -> 97.53 / 90.81 / 91.87 %; p95
distance of the landing maps 2.4-2.7 -> 2.1-2.4 mm. But on held-out seeds 12-23 (``q6.sh``) ``full`` went 5.551 -> 5.653
mm at 346x260 (+0.102 +- 0.253, 4 of 12 better) and 6.445 -> 6.490 mm at 240x180 (+0.045 +- 0.216, 5 of 12): over seeds
0-23, -0.02 / -0.04 mm with 11 of 24 better at each resolution, within the paired spread (per-seed differences of
+-0.3-2 mm from any small map change). So :attr:`evpose.mapping.build.MapBuildConfig.step_lines` is off by default. Why
so little: with the simulator's true edges in place of the built map's points (every point moved onto its nearest true
edge, its attributes kept; ``mapx.py``) ``full`` gives 4.241 mm at 346x260 and 5.620 mm at 240x180 (seeds 0-11, against
4.471 / 5.313 on this builder's map), and the painted points alone moved 4.452 / 5.367; but the top rims alone on the
truth give 3.314 / 4.871 mm (from 4.621 / 5.438 on the map without step lines; the pad's alone 4.394 at 346x260, the
crates' and buildings' alone 3.817) while the feet alone on the truth cost 0.1 mm at 240x180: this fit mends the pad's
rims, feet included, and leaves the crease-snapped top rims (1.84 mm RMS, bias -0.43 mm near the pad), which weigh most
(:mod:`evpose.tracker.event_registration`, session 30).
"""

from __future__ import annotations

import numpy as np


def _robust_line(t: np.ndarray, a: np.ndarray, inlier: float, iters: int = 4) -> tuple[float, float, np.ndarray]:
    """(offset, slope, inlier mask) of ``a = offset + slope * t`` by least squares, refitted to the points within
    ``max(inlier, 3 x MAD sigma)`` of the previous fit."""
    keep = np.ones(t.size, bool)
    off, slope = float(np.median(a)), 0.0
    for _ in range(iters):
        A = np.stack([np.ones(int(keep.sum())), t[keep]], axis=1)
        off, slope = np.linalg.lstsq(A, a[keep], rcond=None)[0]
        r = a - (off + slope * t)
        sigma = 1.4826 * float(np.median(np.abs(r[keep])))
        new = np.abs(r) <= max(inlier, 3.0 * sigma)
        if np.array_equal(new, keep) or new.sum() < 3:
            break
        keep = new
    return float(off), float(slope), keep


def fit_step_runs(
    points: np.ndarray,
    edge_normals: np.ndarray,
    region: np.ndarray,
    movable: np.ndarray,
    cloud: np.ndarray,
    labels: np.ndarray,
    tree,
    plane_c: np.ndarray,
    plane_n: np.ndarray,
    radius: float,
    min_offset: float,
    max_offset: float,
    max_shift: float,
    parallel_cos: float,
    min_run_points: int = 20,
    min_face_points: int = 8,
    min_span: float = 0.5,
    max_slope: float = 0.25,
    inlier: float = 0.01,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Put the ``movable`` contour points of each straight run onto the line fitted to its step face's points.

    ``points`` / ``edge_normals`` (M, 3) (unit normals; a run's points share one exactly), ``region`` (M,),
    ``cloud`` (N, 3) with region ``labels`` (N,) and its cKDTree ``tree``; ``plane_c`` / ``plane_n`` (R, 3)
    the regions' planes. Face points: within ``radius`` of a run point, not of the run's region nor of a
    region whose normal is within ``parallel_cos`` of its plane's, ``min_offset`` to ``max_offset`` off the
    plane, within ``max_shift`` across the run's own (least-squares) line. A run needs ``min_run_points``
    points; a tilted line needs ``min_face_points`` face points spread over ``min_span`` of the run's length
    and a slope under ``max_slope``, else the run is moved by the face points' median offset (at least 3 of
    them). ``inlier``: metres, the least trimming distance of the robust fit.
    Returns the points, their normals and a mask (M,) of the points placed by a fit.
    """
    out_p, out_n = points.copy(), edge_normals.copy()
    fitted = np.zeros(points.shape[0], bool)
    sel = np.flatnonzero(movable)
    if sel.size == 0:
        return out_p, out_n, fitted
    keys = np.concatenate([region[sel, None].astype(np.float64), edge_normals[sel]], axis=1)
    _, group = np.unique(keys, axis=0, return_inverse=True)
    group = group.reshape(-1)
    for g in range(int(group.max()) + 1):
        idx = sel[group == g]
        if idx.size < min_run_points:
            continue
        r = int(region[idx[0]])
        nr = plane_n[r]
        e = edge_normals[idx[0]]
        d = np.cross(nr, e)
        if np.linalg.norm(d) < 0.5:
            continue
        d /= np.linalg.norm(d)
        c = points[idx].mean(axis=0)
        t_run = (points[idx] - c) @ d
        a_run = (points[idx] - c) @ e
        off0, slope0 = np.polyfit(t_run, a_run, 1)[::-1] if np.ptp(t_run) > 0 else (float(a_run.mean()), 0.0)
        length = float(np.ptp(t_run))
        # Face points near the run (queried at points every ~radius/2 along it: the run is dense).
        step = max(1, int(idx.size * 0.5 * radius / max(length, 1e-9)))
        cand = tree.query_ball_point(points[idx[::step]], radius)
        cand = np.unique(np.concatenate([np.asarray(x, np.int64) for x in cand])) if len(cand) else np.zeros(0, int)
        if cand.size == 0:
            continue
        lab = labels[cand]
        ok = lab != r
        other = np.maximum(lab, 0)
        ok &= (lab < 0) | (np.abs(plane_n[other] @ nr) < parallel_cos)
        rel = cloud[cand] - c
        off_plane = np.abs((cloud[cand] - plane_c[r]) @ nr)
        ok &= (off_plane >= min_offset) & (off_plane <= max_offset)
        t_all = rel @ d
        a_all = rel @ e
        ok &= (t_all >= t_run.min()) & (t_all <= t_run.max())
        # Gathered about the run's own line, then again about the fitted one: a traced run can be tilted
        # by several degrees (a notch in a sparse rim), its ends then a shift's width off the face.
        off, slope = float(off0), float(slope0)
        found = False
        for _ in range(2):
            near = ok & (np.abs(a_all - (off + slope * t_all)) <= max_shift)
            t, a = t_all[near], a_all[near]
            if t.size < 3:
                break
            found = True
            if t.size >= min_face_points and np.ptp(t) >= min_span * length:
                off, slope, keep = _robust_line(t, a, inlier)
                if abs(slope) > max_slope or keep.sum() < min_face_points:
                    off, slope = float(np.median(a)), 0.0
            else:
                off, slope = float(np.median(a)), 0.0
        if not found:
            continue
        p_plane = points[idx] - np.outer((points[idx] - c) @ e, e)  # on the run's centre line, own plane
        out_p[idx] = p_plane + np.outer(off + slope * t_run, e)
        n_new = e - slope * d
        out_n[idx] = n_new / np.linalg.norm(n_new)
        fitted[idx] = True
    return out_p, out_n, fitted
