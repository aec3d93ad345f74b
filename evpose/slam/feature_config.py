"""Feature detection and tracking settings of the map-free SLAM (:class:`FeatureConfig`): FAST with a bucketing grid, KLT.

Kept in its own module: most of its fields carry the measurements that set them.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class FeatureConfig:
    """FAST detection with a bucketing grid and pyramidal KLT tracking (both OpenCV)."""

    fast_threshold: int = field(default=8, metadata={"min": 1, "max": 80, "step": 1, "unit": "grey levels"})
    """FAST intensity threshold on the 8-bit normalised image, grey levels."""
    min_eigen_quality: float = field(default=0.001, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "ratio"})
    """FAST corners need a Shi-Tomasi score of at least this share of the image's best, ratio. Many tracks sit on
    straight edges (where KLT slides along the edge), yet fewer, cornerier ones starve the map: landing event-only
    seeds 0-11 (``MciConfig.reference_fraction`` 1.0, mean ATE 3.16 %, 2 of 12 within 2 %): 0.01 -> 3.94 % (0 of 12,
    tracked at least 74.8 %), 0.03 -> 5.02 % (0, 50.0 %). Triangulating only tracks whose structure tensor (11 px)
    had an eigenvalue ratio of at least 0.1 in the keyframe MCI: 3.79 % (0 of 12); only edge tracks that moved across
    their edge (|cos| to the gradient 0.3 / 0.5): 2.98 / 4.61 % (2 of 12 each). New points within 2 / 3 times the
    keyframe's median depth: 3.36 / 2.86 % (1 / 4 of 12)."""
    blob_max_quality: float = field(default=0.0, metadata={"min": 0.0, "max": 0.5, "step": 0.001, "unit": "ratio"})
    """FAST corners whose Shi-Tomasi score is below this share of the image's best (as ``min_eigen_quality``) and whose
    structure tensor over the ``klt_window_px`` square is near isotropic (eigenvalue ratio above ``blob_min_ratio``)
    are not detected: weak dots, not corners or edges (0: no test), ratio. Session 42 (module notes of
    :mod:`evpose.slam.edge_slide`: such tracks drift 0.67-0.83 of the time, against 0.17-0.52 for strong ones). 0.01,
    paired against main: indoor seeds 0-18 1.899 -> 2.042 % (+0.14 +- 0.14, 7 better, 12 worse; within both targets
    13 -> 10, least tracked 0.860 -> 0.712), landing 0-4 1.363 -> 1.633 % (+0.27 +- 0.45, 2 better); step shortness
    (pnp41's h_rel) indoor 0-8 -0.270 -> -0.353, landing 0-4 -0.118 -> -0.092. Off."""
    blob_min_ratio: float = field(default=0.4, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """``blob_max_quality``: smaller-over-larger eigenvalue ratio above which a weak corner counts as a dot, ratio."""
    grid_cols: int = field(default=8, metadata={"min": 1, "max": 32, "step": 1, "unit": "cells"})
    """Bucketing grid columns, cells."""
    grid_rows: int = field(default=6, metadata={"min": 1, "max": 32, "step": 1, "unit": "cells"})
    """Bucketing grid rows, cells."""
    per_cell: int = field(default=4, metadata={"min": 1, "max": 50, "step": 1, "unit": "features"})
    """Strongest features kept per grid cell, features."""
    min_distance_px: float = field(default=8.0, metadata={"min": 1.0, "max": 40.0, "step": 1.0, "unit": "px"})
    """New features keep this far from existing tracks, pixels."""
    border_px: int = field(default=8, metadata={"min": 0, "max": 40, "step": 1, "unit": "px"})
    """Features closer than this to the image border are ignored, pixels."""
    min_support_ratio: float = field(default=0.0, metadata={"min": 0.0, "max": 20.0, "step": 0.25, "unit": "ratio"})
    """A corner needs at least this multiple of the image's mean event count per ``support_window_px`` square around it
    (isolated noise events look like corners; 0 disables the test), ratio. On the indoor room most of the 150 tracks sit
    on noise events in sparse stretches (KLT keeps 1-9 % of them per MCI there), yet event-only seeds 0-3 got worse
    with the test: 2 / 4 / 8 -> ATE 11.99 / 19.64 / 10.80 %, tracked 51.2 / 45.8 / 38.5 % (off: 8.57 %, 52.4 %).
    Dropping the noise events themselves before window selection (session 12, the front end's consistency filter,
    :class:`evpose.frontend.noise_filter.ConsistencyNoiseFilter`, not kept): seeds 0, 1 without coasting, 5 / 10 ms ->
    ATE 9.82 -> 10.73 / 14.36 %, tracked 53.2 -> 40.9 / 39.6 % (the filtered blank-wall stretches fall below
    ``min_event_rate`` and give no MCI, and the room's edges alone leave 20-50 tracks); seeds 0-3 with
    ``TrackingConfig.coast_s`` 0.4: 6.84 -> 12.29 %, 80.2 -> 47.2 % (with ``min_event_rate`` 0.1: 11.35 / 57.3).
    Session 13, the same test on every MCI-to-MCI track's new position (tracks dropped below 1.0; removed), landing
    event-only seeds 0-11 (``/tmp/s13/slamedge/exp.py``): mean ATE 2.52 -> 3.19 %, within 2 % 5 -> 2 of 12, tracked at
    least 96.5 -> 88.0 %. Leaving points triangulated from tracks below 1.0 out of the local BA (pose tracking still
    using them; removed): seeds 0-11 2.52 -> 2.48 % (median 2.21 -> 1.72, within 2 % 5 -> 8), seeds 12-23 3.62 -> 2.94 %
    (3 -> 4), but indoor event-only seeds 0-3 6.84 -> 11.14 % (worse on all four), tracked 80.2 -> 76.7 %; with
    ``TrackingConfig.ba_edge_along_sigma_px`` 3, seeds 0-11: 3.26 % (4 within 2 %)."""
    support_window_px: int = field(default=7, metadata={"min": 3, "max": 31, "step": 2, "unit": "px"})
    """Side of the square the support test counts events in, pixels (odd)."""
    klt_window_px: int = field(default=23, metadata={"min": 5, "max": 51, "step": 2, "unit": "px"})
    """KLT block size, pixels (odd). Landing event-only seeds 0-11, 60 runs (``MciConfig.reference_fraction`` 1.0):
    15 -> mean ATE 3.34 -> 4.13 % (tracked at least 79.0 %), 31 -> 3.34 % (within 2 % 9 -> 12 of 60). KLT on a
    straight edge measures only the motion across it (``TrackingConfig.ba_edge_along_sigma_px``). Session 13, replacing
    the along-edge part of such tracks' motion (structure-tensor eigenvalue ratio below 0.1 over 11 px) by that of a
    RANSAC homography of the corner tracks with event support (removed): landing event-only seeds 0-11 mean ATE 2.52 ->
    3.15 % (median 2.21 -> 2.15, within 2 % 5 -> 4, tracked at least 96.5 -> 83.9 %), the summed keyframe-to-keyframe
    x-rotation error per run (median over the seeds) 8.6 -> 5.4 deg; with ``ba_edge_along_sigma_px`` 3: 2.54 % (5).
    Session 14, re-tracking every MCI-to-MCI track at full resolution with an 11 px window from the 23 px result
    (kept when within 2 px): 2.87 % (5 of 12, worst 5.39); dropping tracks that refinement moved over 0.7 px left
    seeds 0-3 59.7-91.8 % tracked at 5.5-7.1 % ATE (removed). Session 17, indoor event-only seeds 0-7: 31 -> time
    tracked from the events 44.7 -> 49.4 % but ATE 7.39 -> 10.55 % (:mod:`evpose.slam.event_coasting`). Session 19,
    starting event-only MCI-to-MCI KLT where the map's constant-velocity pose moves each mapped track (the others by the
    homography those moves fit), against the along-edge lag of tracks started at zero flow (removed): landing seeds
    0-23 1.82 -> 2.81 % (within 2 % 19 -> 14, paired +0.98 +- 0.52, worst 10.82 %, 2-3 maps on four seeds). Session 22
    (``/tmp/s22/turn9``, removed: commit d6c2af7; the turn's step errors, module notes of :mod:`evpose.slam.features`),
    landing seeds 0-23 (defaults 1.80 %, 20 within 2 %), paired: 31 px 2.13 % (18; +0.33 +- 0.27), though in the sharp
    turn (seeds 0, 4, 10) the median across-flow step fell 0.58 -> 0.47 px (7.0 -> 3.8 px^2/s); 31 px only into MCIs
    with fewer events than 0.5 / 0.6 / 0.7 / 0.75 of the last 20 MCIs' median 2.04 / 1.83 / 2.24 / 1.97 % (14 / 17 / 15 /
    12; +0.24 +- 0.16 / +0.04 +- 0.14 / +0.45 +- 0.25 / +0.17 +- 0.18), 41 px at 0.6 2.34 % (13; +0.54 +- 0.32), pixels."""
    klt_upsample: float = field(default=2.0, metadata={"min": 1.0, "max": 4.0, "step": 0.25, "unit": "ratio"})
    """MCI-to-MCI KLT (event-only and event-inertial; measured event-only) runs on the MCI rendered again on a grid this
    many times finer than the sensor's, its events splatted at their warped sub-pixel positions with
    ``klt_upsample_sigma_px`` (1: the MCI itself, off), ratio. FAST detection, keyframe images and everything else keep
    the sensor-grid MCI. Session 24 (full
    figures in the module notes of :mod:`evpose.slam.features`): 2x with sigma 0.5 cuts the per-step across-flow error
    about 20 % on the landing's legs but only 6-10 % in its sharp turn; over 240 landing runs (seeds 0-47 under the
    defaults and four neutral perturbations) it moves the mean ATE 2.23 -> 1.95 % (paired -0.28 +- 0.14 points), the
    median 1.69 -> 1.52 and the runs within 2 % 163 -> 204, but the runs over 5 % 11 -> 15, gathered on seeds 17, 19
    and 36; with the defaults on seeds 0-23 1.80 -> 2.10 %; indoor seeds 0-7 6.84 -> 11.23 %; CPU per MCI 21.7 ->
    43-45 ms. 1.5x (28 ms): 2.23 -> 2.10 % (-0.13 +- 0.17), within 2 % 163 -> 199, over 5 % 11 -> 21. With the
    cheaper fine pass that is now the default (``klt_upsample_window_px`` 35, ``klt_upsample_scale_stride`` 2; session
    24, ``fine9``): 28.3 ms per MCI (the defaults 22.9, 47 px 42.6, same process), the 240 runs 1.85 % (within 2 % 204,
    over 5 % 12, gathered on seeds 10 and 36), seeds 0-23 with the defaults 1.80 -> 1.59 % (20 -> 23 within 2 %), 24-47
    2.09 -> 1.86 % (15 -> 21); indoor seeds 0-7 6.84 -> 8.93 % (6 of 8 worse). Still off: indoor worse, runaways.
    Session 25 (``/tmp/s25/auto9``; module notes of :mod:`evpose.slam.fine_grid`): indoors the fine grid keeps fewer
    steps (0.562 -> 0.486; KLT stops converging in the sparse MCIs) and makes them no more precise; so it now waits for
    a warm-up of dense MCIs (``klt_upsample_min_events_per_px``, ``klt_upsample_warmup_mcis``), which the indoor rooms
    never pass. With that, 2 (was 1): landing seeds 0-23 1.80 -> 1.44 % (24 of 24 within 2 %), 24-47 2.09 -> 1.70 %
    (19), 48-71 2.17 -> 1.82 % (11 -> 20; seed 66 8.35 %), the 240 runs 2.23 -> 1.70 % (within 2 % 209, over 5 % 7;
    paired -0.53 +- 0.14 points); indoor unchanged (seeds 0-7 6.84 %, 8-11 7.98 %); E-I-C2 landing 0-23 ATE 0.82 -> 0.94
    %, RPE at most 0.0034 m/m and 0.0020 deg/m; CPU per MCI landing 22.8 -> 28.6 ms, indoor 15.1 -> 15.0. Session 26
    (``/tmp/s26/speed26``, module notes of :mod:`evpose.slam.mci`): the MCI stage in numba and KLT without its unread
    error pass, outputs bit-identical: CPU per MCI with this default landing seeds 0-3 31.1 -> 25.8 ms (main alongside,
    loaded machine; means 36.2 -> 30.8), indoor seeds 0-1 16.4 -> 12.2 ms."""
    klt_upsample_sigma_px: float = field(default=0.5, metadata={"min": 0.3, "max": 2.0, "step": 0.05, "unit": "px"})
    """``klt_upsample``: the fine MCI's splat, sensor pixels (the sensor-grid MCI's is ``EventImageConfig.sigma_px``).
    0.5 (was 0.6 before session 24's ``fine9``, which measured every 240-run figure at 0.5)."""
    klt_upsample_window_px: int = field(default=35, metadata={"min": 0, "max": 101, "step": 2, "unit": "px", "zero": "automatic"})
    """``klt_upsample``: KLT block size on the fine grid, fine pixels (odd; 0: ``klt_window_px`` scaled, rounded up to
    odd: 47 at 2x; the viewer offers the 0 as a checkbox, ``zero``). Session 24 (``/tmp/s24/fine9``, 2x, sigma 0.5, ``klt_upsample_scale_stride`` 2; CPU per MCI by
    ``cpubench.py``, landing seeds 0-3 alternating in one process, against the defaults' 22.9 ms): 47 px 42.0 ms, 41 px
    29.7, 35 px 28.3, 31 px 29.4 (KLT forward and backward, synthetic, 15.7 / 7.4 / 8.1 ms at 47 / 35 / 31 px). 35 px
    over the 240 landing runs of ``klt_upsample`` (seeds 0-47 under the defaults and session 23's four perturbations):
    mean ATE 1.85 % (47 px: 1.95, ``klt_upsample`` off: 2.23), median 1.41 (1.52, 1.69), within 2 % 204 (204, 163), over
    5 % 12 (15, 11; seeds 10 and 36), paired against 47 px -0.10 +- 0.13 points (142 better), against off -0.38 +- 0.15
    (169 better); so 35 (was 0). 41 px, defaults only: seeds 0-23 1.33 % (24 within 2 %), 24-47 2.30 % (19; 26 / 36
    9.2 / 10.8 %)."""
    klt_upsample_levels: int = field(default=3, metadata={"min": 0, "max": 6, "step": 1, "unit": "levels"})
    """``klt_upsample``: pyramid levels above the fine image, levels. Session 24 (``/tmp/s24/fine9``, 35 px window): 2
    levels 21.7 ms per MCI (3: 28.3, the defaults 22.9) but landing seeds 0-23 / 24-47 8.53 / 8.54 %
    (0 within 2 %; share of time tracked from the events 0.97 -> 0.46): the 2x grid needs the third level's reach."""
    klt_upsample_scale_stride: int = field(default=2, metadata={"min": 0, "max": 8, "step": 1, "unit": "px"})
    """``klt_upsample``: the fine image's 8-bit robust maximum from every this-many-th row and column only, scaled in
    OpenCV (0: all of them in numpy, as the sensor-grid MCI; :func:`evpose.slam.fine_grid.fine_to_uint8`), fine pixels.
    Session 24 (``/tmp/s24/fine9``): synthetic 692x520 image 5.9 -> 1.1 ms (stride 1 3.6, 3 0.4), 8-bit values within
    2; in the pipeline (landing seeds 0-3, few non-zero pixels) only 42.6 -> 42.0 ms per MCI. 2x, sigma 0.5, 47 px,
    landing seeds 0-23: 2.04 % (20 within 2 %) against 0's 2.10 % (20), paired -0.06 +- 0.45 points; so 2 (was 0)."""
    klt_upsample_min_events_per_px: float = field(default=0.15, metadata={"min": 0.0, "max": 2.0, "step": 0.005,
                                                                          "unit": "events/px"})
    """``klt_upsample``: the fine grid is used only where the MCIs hold at least this many events per sensor pixel (0:
    always), events per pixel; judged per MCI, or once per recording (``klt_upsample_warmup_mcis``). An MCI without a
    fine image has its KLT steps in and out on the sensor grid. Session 25 (``/tmp/s25/auto9``, module notes of
    :mod:`evpose.slam.fine_grid`): the fine grid loses steps in MCIs under ~3000 events (346x260; 0.81-0.84 of the
    sensor grid's kept), only indoors. Per MCI (warm-up 0): 0.035 landing seeds 0-23 1.59 % (as always on), indoor 0-7
    8.04 % (off 6.84); 0.1 landing 2.29 % (the turn left on the sensor grid), indoor 6.64 %. Once per recording over 10
    MCIs: 0.15 sits between the warm-up medians of the indoor rooms (seeds 0-11: 0.039-0.089) and of the landing (seeds
    0-71: 0.185-0.247; ``/tmp/s25/auto9/warmup.py``), so any floor between gives the same runs there; 0.15 (was 0).
    Session 26 (``/tmp/s26/sparse26``: ``dens2.py`` the warm-up median, ``dimx.py`` the ATE): a landing with fewer
    events reads as a room. Dimmed (events before 1.2 s kept with probability 0.4) seeds 0-7: warm-up median
    0.070-0.089; thinned to 0.5 throughout: 0.083-0.119; so the whole recording runs on the sensor grid, though these
    MCIs hold 4000-12000 events (under 3000: 0-4 % of them, but 45 % on the dimmed seed 7, whose ``N_e`` runs down:
    ``EventWindowConfig.noise_residual_px``). The fine grid forced on (0): dimmed 4.38 -> 2.46 % (paired -1.92 +- 0.91,
    7 of 8 better; seeds 4 / 5 8.36 / 7.17 -> 2.18 / 1.41 %, seed 7 10.65 -> 8.93), thinned 4.54 -> 2.84 % (0 of 8
    within 2 % either way). The warm-up medians overlap the rooms' (0.039-0.089), so no floor separates them: a floor of
    0.095 would turn it on for 7 of the 8 thinned runs and none of the dimmed, 0.007 above the highest room."""
    klt_upsample_warmup_mcis: int = field(default=10, metadata={"min": 0, "max": 200, "step": 1, "unit": "MCIs"})
    """``klt_upsample_min_events_per_px``: 0 judges every MCI by its own events; N > 0 judges once, by the median over
    the recording's first N MCIs (tracked on the sensor grid), and keeps that choice to the end, MCIs. Session 25
    (``/tmp/s25/auto9``), floor 0.15, landing seeds 0-23: 10 MCIs (0.4 s) 1.44 % (24 within 2 %; the fine grid from the
    first MCI: 1.59, 23), 5 MCIs 1.45 % (median 1.27, 23; worst 4.49), 20 MCIs 1.46 % (median 1.29, 21; worst 2.86);
    indoor seeds 0-7 6.84 % with 10 and 5 (no room passes either). So 10 (was 0)."""
    klt_upsample_refine: bool = False
    """``klt_upsample``: track on the sensor-grid MCIs as usual, then refine each result by single-level KLT on the fine
    grid started there (the forward-backward test on the fine pass), instead of a full pyramid on the fine grid."""
    klt_levels: int = field(default=2, metadata={"min": 0, "max": 5, "step": 1, "unit": "levels"})
    """KLT pyramid levels above the base image, levels. Session 27 (``/tmp/s27/turn27/kltdiag.py``): in the indoor rooms'
    turns the true MCI-to-MCI step is a median 2.8 px (90th percentile 4.2) and 4 levels keep no more tracks (0.51 ->
    0.50 of all per step, map-point tracks 0.66 -> 0.64; module notes of :mod:`evpose.slam.event_coasting`)."""
    klt_min_eig: float = field(default=1e-4, metadata={"min": 0.0, "max": 0.1, "step": 1e-4, "unit": "(grey levels/px)^2"})
    """OpenCV KLT's ``minEigThreshold``: a track whose window's spatial-gradient matrix has a smaller minimum eigenvalue
    (divided by the window's pixel count, on OpenCV's scaled derivatives) is lost at the base level; 1e-4 is OpenCV's
    default, (grey levels/px)^2 as OpenCV scales them. Applies to every KLT call through
    :func:`evpose.slam.features.track_features` (the fine grid's too). Session 42 (``/tmp/s42/drift42``, module notes
    of :mod:`evpose.slam.edge_slide`: the drifting tracks are the weak ones): per-step minimum eigenvalues, median 0.0048
    indoors, 0.026 / 0.0029 on the landing's sensor / fine grid. 3e-4 (a 10th / 2nd / 4th percentile): event-only ATE
    (``evpose eval --atlas --correct-scale``) paired against main, indoor seeds 0-8 2.008 -> 1.982 % (-0.03 +- 0.22, 4
    better, 5 worse; least tracked 0.883 -> 0.832), landing 0-2 1.331 -> 3.220 % (+1.89 +- 1.75; seed 2 0.93 -> 6.31 %);
    step shortness (pnp41's h_rel) indoor -0.270 -> -0.272, landing -0.118 -> -0.145. So 1e-4."""
    klt_max_bidir_error_px: float = field(default=1.0, metadata={"min": 0.1, "max": 5.0, "step": 0.1, "unit": "px"})
    """Tracks whose forward-backward KLT error exceeds this are dropped, pixels. Landing event-only seeds 0-11, 60 runs
    (see ``MciConfig.reference_fraction``; 1.0 there): 0.5 -> mean ATE 3.34 -> 3.38 %, within 2 % 9 -> 3 of 60. Session 24
    (``/tmp/s24/sr9``, whether ``klt_upsample``'s gain in typical runs came from the more steps it keeps): 1.5 keeps 0.675
    of the steps (defaults 0.652, 2x grid 0.736; landing seeds 0, 4, 10) and over landing seeds 0-23 under the defaults
    and ``TrackingConfig.ba_huber_px`` 1.9 / 2.1 gives 2.63 / 2.41 / 2.00 % (72 runs: 2.11 -> 2.35 %, median 1.60 ->
    1.74, within 2 % 50 -> 46, paired +0.23 +- 0.23 points, 35 better). Session 40 (``/tmp/s40/cv40``: ``surv.py``,
    ``run2.py``): indoors the map tracks of a young event-only map (< 0.1 s) pass this test at a rate of 0.62 per MCI
    (0.85 converge; landing 0.87-0.93, indoor maps older than 0.3 s 0.89), so a 12-16-point map falls under
    ``TrackingConfig.min_inliers`` within a few MCIs. A prototype letting those tracks (young maps only) pass at 2 px:
    indoor seeds 0-15 1.91 -> 2.09 % (paired +0.18 +- 0.11, 6 better, within target 12 -> 10); not kept."""
    klt_first_step_max_residual_px: float = field(default=0.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "px"})
    """A new track whose first MCI-to-MCI step lies farther than this from a RANSAC homography of the older tracks'
    steps is dropped (0: no test), pixels. Session 14 (``/tmp/s14/tracknoise``): the event-only landing's per-track
    errors (``TrackingConfig.ba_huber_px``) start at the first step, heavy-tailed (seeds 1 / 3: median 1.06 / 0.88
    px, 90th percentile 6.3 / 6.5 px, 41 / 37 % over 1.5 px; later steps 0.5-0.8 px); this residual correlates with
    that step's true error at 0.86 / 0.93, and of the first steps it puts over 2 px (26 %) 90-92 % are over 1.5 px
    off. At 1.5 px the share of one-step-old observations off by over 1.5 px fell to 15 / 13 % (all ages 53 / 50 ->
    48 / 46 %). Landing event-only (defaults: seeds 0-11 2.52 %, 5 of 12 within 2 %; seeds 12-23 3.62 %, 3): 3 px
    1.75 % (8, max 2.65; paired -0.77 +- 0.26 points, 11 better) and 2.52 % (8; -1.10 +- 0.67, 9 better); with
    ``target_tracks`` 145 (a perturbation) 3.13 -> 2.24 % (2 -> 5; -0.89 +- 0.53, 7 better); seeds 0-11 at 1.5 / 2 /
    4 px 2.73 / 2.82 / 2.38 % (7 / 6 / 5). E-I-C2 landing seeds 0-11 at 3 px: ATE 0.94 -> 0.97 %, RPE at most 0.0032
    m/m and 0.0022 deg/m (0.0050, 0.0022). Indoor event-only (multi-map, much coasting) seeds 0-3: 6.84 -> 12.21 %
    (all four worse), 4-7: 10.80 -> 13.18 % (two worse; tracked 82.5 -> 85.3 %), though the gate removed bad first
    steps there too (seed 0: 51 -> 39 % over 1.5 px) and the homography holds there as well as on the landing (its
    inlier share of the older tracks' steps at 3 px, median per MCI: indoor seed 0 0.91, landing seeds 1 / 3 0.89 /
    0.91), so it stays off until indoor tracking is stable enough to judge it. Gating only while tracking a map (not
    during the two-view initialisation): landing 3.13 %, indoor 6.53 % (tracked 80.2 -> 72.5 %); only during the
    initialisation: landing 2.31 % (8). Judging each track's first three steps 2.25 % (7); the median step of the 6
    nearest older tracks in place of the homography 2.13 % (6), indoor 9.89 %. Also tried and removed: the same test
    on every track's every step (2 px: 3.22 %, 0 of 12; 1 px: seeds 0-6 3.6-7.3 %, initialisations delayed);
    dropping tracks older than 8 MCIs (their map points re-found by projection) 5.41 % (3; 4 MCIs: seeds 0-3
    4.3-13.1 %, coasting); re-tracking every track from its first MCI (single-level KLT from the chained position,
    kept within 1 / 2 px) 2.48 / 4.23 % (6 / 4), with this gate 2.92 % (7). That re-tracking left the track errors
    as they were (seed 1: 53 % over 1.5 px either way): they sit in the event images' appearance of the corners, not
    in KLT's chaining. Lead, on main after the blank-wall coasting: 3 px landing 0-11 1.75 % (8) as above; indoor
    seeds 0-3 / 4-7 8.43 / 11.44 -> 11.46 / 12.22 % (tracked 95.5 / 91.9 -> 90.1 / 88.0 %), hence off; 3 px with
    ``ba_edge_along_sigma_px`` 3 landing 0-11 2.40 % (5 of 12, worst 4.60)."""
    klt_curvature_gain: float = field(default=0.0, metadata={"min": 0.0, "max": 3.0, "step": 0.05, "unit": "ratio"})
    """Each MCI-to-MCI step removes the change of the shift a constant-velocity warp leaves under image acceleration
    (:func:`evpose.slam.track_step.remove_curvature_shift`; 0: off), ratio of the model's ``a T^2 / 24``. Session 15
    (``/tmp/s15/turnbias``, see the module notes of :mod:`evpose.slam.features`): the shift is there but small. On the
    event-only landing (seeds 1, 2, 3, 7) the true track errors regress on the model's summed shift since birth (true
    image acceleration) at 1.6-2.1 times the model, R^2 0.6-1.1 %, the model's shift 0.11-0.14 px RMS; from the tracks'
    own acceleration (what this option uses) at 0.6-0.8 times. Per step it moves a track by 0.02 px median, 0.65 px at
    the 99th percentile (landing seed 1; indoor seed 0: 0.008 / 0.67 px, at most 14 px), and leaves the observation
    errors as they were (seeds 1 / 3, gain 1: median 1.64 / 1.50 -> 1.51 / 1.61 px). Landing event-only seeds 0-11
    (defaults 2.52 %, 5 of 12 within 2 %): gain 0.5 / 1 2.64 / 2.00 % (4 / 6), across the motion only
    (``klt_curvature_perpendicular``) 1.92 / 3.05 % (8 / 7). Over 96 runs (seeds 0-23, the defaults and the neutral
    perturbations ``ba_huber_px`` 1.9 / 2.1 and ``reprojection_threshold_px`` 2.4), 0.5 across: mean ATE 2.77 -> 2.50 %,
    median 2.23 -> 2.02, within 2 % 40 -> 46, paired -0.28 +- 0.17 points, 55 better; with ``klt_curvature_max_px``
    0.3: -0.27 +- 0.20 (47 within 2 %); gain 1 in full over 60 runs -0.41 +- 0.25. E-I-C2 landing seeds 0-3 (0.5
    across): ATE 0.81 -> 0.68 %, RPE at most 0.0031 m/m and 0.0016 deg/m. But on top of
    ``klt_first_step_max_residual_px`` 3 (landing seeds 0-23, 1.75 / 2.52 %) it is worse: 2.72 / 2.12 %, within 2 % 16
    -> 9 of 24, paired +0.29 +- 0.37. Indoor event-only seeds 0-3 with the same four settings and seeds 4-7 with the
    defaults (20 runs): 8.80 -> 9.03 % (paired +0.23 +- 0.66, 8 better; seeds 0-3 defaults 8.43 -> 10.78 %, tracked
    95.5 -> 92.8 %; seeds 4-7 11.44 -> 9.87 %); with the 0.3 px clip, seeds 0-3, 16 runs: 8.14 -> 9.96 % (+1.82 +-
    1.05). So off. CPU 0.16 ms per MCI at 150 tracks. Lead, after session 15's two-view initialisation
    (``InitializationConfig.homography_fit_share``; defaults: landing seeds 0-11 / 12-23 2.37 / 3.18 %, 7 / 6 within 2
    %, indoor seeds 0-7 7.39 %), 0.5 across (``/tmp/s15/lead/exp.py cg ...``): landing 2.10 / 2.80 %, 9 / 4 within 2 %
    (13 of 24 either way), indoor 9.25 % (tracked 93.7 %, min 85.4): still off."""
    klt_curvature_perpendicular: bool = False
    """``klt_curvature_gain``: only the part across each track's motion (the turn's), not along it."""
    klt_curvature_max_px: float = field(default=0.0, metadata={"min": 0.0, "max": 5.0, "step": 0.05, "unit": "px"})
    """``klt_curvature_gain``: longest shift a track is credited with (0: no clip), pixels."""
    klt_min_ncc: float = field(default=0.0, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """MCI-to-MCI tracks whose 11x11 patches (previous vs current MCI) correlate below this are dropped (0: no test).
    KLT started at the gyro-predicted flow passes its forward-backward test on blob-like event images even where
    the scene changed, confirming its own prediction; the patch correlation does not (see the measured figures in
    ``InertialConfig.ba_gyro_prior_uninit_deg``). Synthetic scene switch with that prior at 0.02 (measured before
    ``EventWindowConfig.max_event_gap_ms``, which bridges it without this test): 0 / 0.2 / 0.3 / 0.6 ->
    ATE 5.5 / 2.7 / 3.3 / 3.8 %, bridged by the IMU from 0.3 up (as without the prior). Landing E-I-C2 seeds 0-23 with
    the prior: 0.3 -> mean ATE 1.09 % (23 of 24 within 2 %, seed 13 6.2 % and 0.0196 m/m), 0.6 -> 1.48 % (21/24);
    without the prior 0.6 -> 7.23 % (15/24, against 4.53 % and 18/24 off). Indoor seeds 0-3 (scale lost either way):
    0.3 with the prior 1/3/6/4 maps, RPE above 0.01 m/m on seeds 1-3 (seed 2 1.95 m/m). So off, ratio."""
    klt_min_support_ratio: float = field(default=0.0, metadata={"min": 0.0, "max": 20.0, "step": 0.25, "unit": "ratio"})
    """Event-only, while a map is tracked: MCI-to-MCI tracks whose new position's ``support_window_px`` square holds
    fewer than this multiple of the MCI's mean event mass per square are dropped (0: no test), ratio. KLT on a patch
    with no events (a blank wall, an edge the motion runs along) stays where it started and still passes the
    forward-backward test (what such tracks are: the module notes of :mod:`evpose.slam.features`). Session 16
    (``/tmp/s16/indoorfe9``; indoor event-only seeds 0-7 with the defaults and the neutral perturbations ``ba_huber_px``
    1.9 / 2.1 and ``reprojection_threshold_px`` 2.4, 32 runs, defaults 7.40 %, tracked at least 79.3 %): 2 -> 5.77 %
    (defaults alone 7.39 -> 5.51 %), paired -1.63 +- 0.61 points, 23 better, tracked mean 93.0 -> 90.1 % (one run 73.2
    %); 3 -> 6.04 % (24 runs, -1.43 +- 0.62). Testing during the two-view initialisation as well delays it (not
    initialised 8 -> 45 MCIs on seed 0): 1.5 / 2 / 3 -> 7.40 (16 runs) / 5.96 / 7.15 %, tracked at least 66.8 / 74.4 /
    66.7 %. An absolute floor of 2 events in the square (state as here) 5.43 % (24 runs, -1.94 +- 0.82), and applied
    only to tracks without a map point (none of them becomes one) 5.38 % (16 runs, -1.91 +- 0.63, tracked at least 85.3
    %). But the event-only landing, whose tracks mostly lie on texture (5 % of them on patches with fewer than 2 events,
    against 75 % indoors), loses visual tracking in the turn with any of these (PnP inliers fall under ``min_inliers``
    and the map coasts), seeds 0-11 (defaults 2.37 %, 7 of 12 within 2 %): 2 -> seeds 0-6 4.03 % against 2.52 (2 of 7
    within 2 % against 5); the 2-event floor 3.36 % (4 of 12), only for tracks without a map point 3.49 % (6 of 12,
    seed 4 5.58 -> 10.28 %); 2 only while 24 supported map-point tracks remain, seeds 0-8 3.34 % against 2.44; a track
    dropped only after two unsupported MCIs in a row, seeds 0-7 4.67 % against 2.54. The same test at detection
    (``min_support_ratio``) 2 / 4: indoor defaults 6.84 / 11.86 %, tracked at least 75.3 / 69.5 %, landing seeds 0-8 3.68
    % against 2.44. Most of the indoor gain is coasting, not better tracks: visually tracked MCIs per run fall 75 -> 47
    and coasted ones rise 103 -> 129 (means over the 32 runs), the 0.84-1.9 s stretch becomes a coasted map that the
    per-map alignment fits within 0.1-3 cm (seeds 2, 4, 5 tracked it visually at 10-22 cm RMS). A test that drops
    nearly every track shows how far that goes: KLT of four 9 px sub-windows 5 px off each diagonal, started at the
    track's flow, any of them off by more than 1.5 px (an occlusion-boundary test) leaves 9-10 MCIs tracked of 177-197
    and gives indoor seeds 0-3 1.35 / 2.13 / 1.70 / 2.86 % at 82-90 % tracked (5-7 maps); landing seeds 0-8 2.0-3.2 %
    at 70-86 %. With two of the four off by more than 3 px: indoor seeds 0-2 10.59 / 6.49 / 4.25 % (defaults 7.84 /
    3.61 / 9.89), landing seeds 0-5 3.95 / 4.70 / 3.78 / 3.50 / 6.83 / 6.91 % (1.50 / 1.72 / 1.87 / 3.06 / 5.58 /
    1.96). So off, ratio."""
    klt_birth_anchor_px: float = field(default=0.0, metadata={"min": 0.0, "max": 30.0, "step": 0.5, "unit": "px"})
    """After each MCI-to-MCI step, tracks at least ``klt_birth_anchor_min_age`` MCIs old are tracked again by KLT from
    the MCI they were born in (at their birth pixel), started at the chained position, and moved where that lands
    within this distance of it and passes the forward-backward test (0: off), pixels (:mod:`evpose.slam.birth_anchor`).
    Session 41, 8 px: ATE landing seeds 0 / 1 1.09 / 1.97 -> 4.95 / 4.17 %, indoor 0-9 1.96 -> 1.76 % (7 of 10 worse); it
    moves a quarter of the tracks by ~0.2 px, as often away from the truth as towards it, since the birth patch
    correlates better with the drifted position than with the birth point's true projection (figures in the module
    notes). So off."""
    klt_birth_anchor_min_age: int = field(default=2, metadata={"min": 1, "max": 100, "step": 1, "unit": "MCIs"})
    """``klt_birth_anchor_px``: youngest track re-anchored, MCIs since its birth."""
    klt_birth_anchor_drop: bool = False
    """``klt_birth_anchor_px``: end the tracks whose re-anchoring fails instead of keeping their chained position.
    Session 41, 8 px: landing seeds 0 / 1 1.09 / 1.97 -> 7.80 / 3.61 %; indoor 0-9 1.96 -> 1.53 % (6 better) at less
    time tracked (least 87.3 -> 78.1 %), held-out indoor 10-12 2.15 -> 1.59 %: more coasting, not better tracks
    (module notes of :mod:`evpose.slam.birth_anchor`). So off."""
    klt_edge_slide_px: float = field(default=0.0, metadata={"min": 0.0, "max": 30.0, "step": 0.5, "unit": "px"})
    """A track is ended once the sum over its MCI-to-MCI steps of the step's component along its birth patch's edge
    direction, minus that of the median step of its ``klt_edge_slide_neighbours`` nearest live tracks, exceeds this
    (0: off), pixels (:mod:`evpose.slam.edge_slide`: the drift pnp41 found lies along the birth edge, relative to the
    neighbours). Session 42 (``/tmp/s42/drift42``, event-only ATE of ``evpose eval --atlas --correct-scale`` paired
    per recording against main; "within" = ATE <= 2 % and tracked >= 80 %): 4 px indoor 0-18 1.899 -> 2.173 % (+0.27 +- 0.28, 7 better,
    12 worse; within 13 -> 9, least tracked 0.860 -> 0.799), held-out 19-25 2.005 -> 2.025 % (+0.02 +- 0.18; within 6
    -> 4), landing 0-4 1.363 -> 2.752 % (+1.39 +- 1.59; seed 0 1.09 -> 8.78 %), 5-8 1.612 -> 1.037 % (-0.58 +- 0.34, 3
    better); on landing 0 / indoor 1
    the inliers 3-20 px off their birth point's true projection 0.41 / 0.37 -> 0.30 / 0.33 of them, still along their
    birth edge (|cos| 0.78 / 0.77), and the step shortness (pnp41's h_rel) indoor 0-8 -0.270 +- 0.075 -> -0.201 +-
    0.050, landing 0-4 -0.118 +- 0.020 -> -0.074 +- 0.023: it shortens the short steps, but the ATE does not follow. 8 px: indoor 0-18 1.899 -> 1.796 % (-0.10 +- 0.17, 9 better,
    10 worse; within 13 -> 14), held-out 19-25 2.005 -> 2.389 % (+0.38 +- 0.50; within 6 -> 3), landing 0-4 1.363 ->
    1.302 % (-0.06 +- 0.13), 5-8 1.612 -> 3.352 % (seed 7 0.96 -> 9.13 %); h_rel indoor -0.242, landing -0.098. Off."""
    klt_edge_slide_renew: bool = False
    """``klt_edge_slide_px``: carry a track that slid on under a new id (no map point; its old point left to the
    projection search, its birth edge measured anew) instead of ending it. Session 42, 4 px: indoor 0-18 1.899 -> 1.905
    % (+0.01 +- 0.21, 9 better, 10 worse; within 13 -> 11, least tracked 0.860 -> 0.781), held-out 19-26 1.942 -> 1.887
    % (-0.06 +- 0.45; within 7 -> 5), landing 0-4 1.363 -> 1.156 % (-0.21 +- 0.24, 3 better), 5-12 1.386 -> 1.342 %
    (-0.04 +- 0.26; within 7 -> 6); h_rel indoor 0-8 -0.247 +- 0.066, landing 0-4 -0.094 +- 0.022 (main -0.270 /
    -0.118). 8 px: indoor 0-18 1.899 -> 2.084 % (+0.18 +- 0.26, 6 better, 13 worse; within 13 -> 12), landing 0-4 1.363
    -> 1.164 % (-0.20 +- 0.25), 5-9 1.497 -> 2.889 % (+1.39 +- 1.82, one run away); h_rel indoor -0.121 +- 0.083, landing
    -0.078 +- 0.020. Off."""
    klt_edge_follow_max_ratio: float = field(default=0.0, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """Tracks born on a patch whose structure tensor (``klt_window_px`` square) has an eigenvalue ratio below this take,
    along their birth edge direction, the median step of their ``klt_edge_slide_neighbours`` nearest live tracks
    instead of their own KLT step (0: off), ratio (:mod:`evpose.slam.edge_slide`). Session 42, 0.25: indoor 0-18 1.899
    -> 1.931 % (+0.03 +- 0.19, 9 better, 10 worse; within 13 -> 11), landing 0-4 1.363 -> 2.150 % (+0.79 +- 0.51, 1
    better); it does not take the drift out (landing 0 / indoor 1: inliers 3-20 px off 0.41 / 0.37 -> 0.43 / 0.41, still
    along the birth edge), h_rel indoor 0-8 -0.312, landing 0-4 -0.155 (main -0.270 / -0.118). Off."""
    klt_edge_slide_neighbours: int = field(default=8, metadata={"min": 2, "max": 50, "step": 1, "unit": "tracks"})
    """``klt_edge_slide_px``: nearest live tracks whose median step a track's step is compared with, tracks."""
    target_tracks: int = field(default=150, metadata={"min": 20, "max": 1000, "step": 10, "unit": "tracks"})
    """New features are detected on an MCI when fewer tracks survive, tracks. Session 17, indoor event-only seeds
    0-7: 300 -> ATE 7.39 -> 8.02 %, time tracked from the events 44.7 -> 40.2 % (:mod:`evpose.slam.event_coasting`)."""
