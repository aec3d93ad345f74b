"""The IMU initialisation on visually tracked keyframes only (``InertialConfig.init_visual``, off by default).

Indoors ~65 % of the E-I-C2 steps before the initialisation are coasted (gyro rotation, last camera-frame velocity):
their keyframes carry no true acceleration, and the visual-inertial alignment over them returns a median 0.25 of the
map's true scale (session 39, ``/tmp/s39/ms39/README.txt``). This option fits the alignment to the keyframes placed by
PnP in the map's newest visual segment only (coasted keyframes and the older re-joined segments, whose scale differs,
are dropped) and refuses the initialisation while those keyframes do not determine the scale (``max_scale_std_ratio``),
so the map waits for a better window instead of taking a wrong scale.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class InitVisualConfig:
    """``InertialConfig.init_visual``: the IMU initialisation over visually tracked keyframes of one visual segment.

    Session 40 (in40, ``/tmp/s40/in40``; truth read by the offline scripts only). Offline (``obs.py``, ``dense.py`` on
    the maps of indoor 0-3 at their IMU init): within the visual stretches (0.03-0.25 s each, 2-21 PnP poses, one per
    re-joined segment) the map's rotations are within 0.03-0.37 deg of the truth but its positions 0.5-7.9 cm off it
    after a similarity fit; the alignment over every PnP-placed MCI pose with one scale per segment returns 0.001-0.1 of
    the true scale (formal std 0.17-30 times the scale), while the true poses at the same times return 0.90-1.02 (std
    <= 1.6 %), and map rotations with true positions 0.95-1.13 on the segments with enough poses: the scale is lost
    to the visual positions' noise, not to the coasted keyframes or the sampling. The same holds over the 0.5-1.0 s
    visual stretches late in the runs, before or after the initialisation (``stretch.py`` on main's final trajectories,
    indoor 0-19, 17 stretches of 52-127 cm): the map's positions are 1.6-5.7 cm RMS off a similarity of the truth (0.6-4.8
    cm of it smooth), its rotations 0.03-0.12 deg; the alignment returns a median 0.01 of the scale (0 of 17 within
    0.8-1.25; smoothed or thinned to 0.1-0.2 s: 0.05-0.29), with the true positions and the map's rotations 0.90 (13 of
    17). No selection of the map's poses makes the initialisation metric indoors; see ``enabled`` for the online runs.
    """

    enabled: bool = False
    """Fit the initialisation to the PnP-placed keyframes of the map's newest visual segment only (thinned to
    ``min_gap_s``) and refuse it unless its scale's standard error is within ``max_scale_std_ratio`` of it.
    Off: session 40 (``/tmp/s40/in40`` ``h.py`` + ``batch.sh``, tag ``iv`` = this on with the defaults below, against
    main's ``rm33``): indoor 0-61 initialised 55 -> 4 runs (the newest segment's visual keyframes rarely reach 6 over
    0.3 s, and then the scale test refuses), ATE without scale correction mean 16.23 -> 28.50 % (+12.3 +- 8.2 points,
    26 better, 29 worse; median 15.74 -> 17.95; worst 23.9 -> 464 %), scale spread (``scale_drift_percent_max``)
    median 849 -> 170 %, both RPE targets 62 -> 55 of 62 (rotation +0.0012 +- 0.0002 deg/m, 45 worse). Landing 0-23:
    never initialised (the 0.05 s-thinned keyframes fail ``max_residual_ratio``, 2.6-2.7 %), ATE 1.04 -> 21.06 %, 0 of
    24 within the translation target. An initialisation at the wrong scale still serves the tracking; refusing it costs
    more than the wrong scale does."""
    min_keyframes: int = field(default=6, metadata={"min": 4, "max": 100, "step": 1, "unit": "keyframes"})
    """Visually tracked keyframes of the newest segment the initialisation needs (after thinning), keyframes."""
    min_span_s: float = field(default=0.3, metadata={"min": 0.0, "max": 10.0, "step": 0.05, "unit": "s"})
    """Time those keyframes must span, s: the acceleration's share of the displacement grows with the span squared."""
    min_gap_s: float = field(default=0.05, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "s"})
    """Thinning of those keyframes (``InertialConfig.init_min_gap_s`` for this fit), s."""
    max_scale_std_ratio: float = field(default=0.2, metadata={"min": 0.0, "max": 5.0, "step": 0.01, "unit": "ratio"})
    """Refuse when the fit's scale standard error exceeds this share of the scale (``InertialConfig.max_scale_std_ratio``
    for this fit; 0 = no such test), ratio."""


def initialize_on_visual_keyframes(kfs: list, segment_start_kf: int, imu, T_cam_imu, time_offset_us: int, ic):
    """:func:`evpose.slam.inertial.initialize_imu` over the visually tracked keyframes (``Keyframe.visual``) of the
    newest visual segment (ids from ``segment_start_kf``) of ``kfs`` with ``ic.init_visual``'s thinning and scale test;
    ``used`` indexes ``kfs``."""
    from dataclasses import replace

    from evpose.slam.inertial import ImuInitResult, initialize_imu, thin_keyframes

    cv = ic.init_visual
    sel = [i for i, k in enumerate(kfs) if k.visual and k.id >= segment_start_kf]
    n = len(thin_keyframes([kfs[i].t_us for i in sel], cv.min_gap_s))
    if n < cv.min_keyframes:
        return ImuInitResult(False, f"{n} visually tracked keyframes in the newest segment < {cv.min_keyframes}")
    span = (kfs[sel[-1]].t_us - kfs[sel[0]].t_us) / 1e6
    if span < cv.min_span_s:
        return ImuInitResult(False, f"visually tracked keyframes span {span:.2f} s < {cv.min_span_s:g}")
    # The same alignment and tests, only over these keyframes, thinned less and with the scale's standard error bounded.
    sub = replace(ic, init_min_gap_s=cv.min_gap_s, max_scale_std_ratio=cv.max_scale_std_ratio)
    res = initialize_imu([kfs[i].t_us for i in sel], [kfs[i].T_wc for i in sel], imu, T_cam_imu, time_offset_us, sub)
    res.used = [sel[k] for k in res.used]
    return res
