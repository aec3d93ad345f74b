"""Which pose updates a tracking session runs: the regular grid, minus the empty updates inside long event gaps.

A session updates the pose at ``t0 + k * dt`` (``k = 1, 2, ...``). Where the events stop for longer than
``TrackerConfig.max_event_gap_ms`` (a recorder paused, two flights in one file, a dropped stream) the updates in
between have nothing to register, and stepping through them was slow and harmful. The updates up to the one that
takes the last event before the gap run as before; one update then stands for the whole gap, at the first grid time
at least ``warmup_ms`` after the first event after it. It reports the track lost ("no events for ... s") and
restarts the tracker there as at the start of the recording (from which pose:
:meth:`~evpose.tracker.session.TrackingSession._restart_after_gap`).

Measured (session 25, demo ``landing`` with everything after 2 s moved later, IMU and ground truth too, ``full``,
``/tmp/s25/cli25/make_gap.py``, ``cmp_gap.py``): a 60 s gap was 12 793 updates, 30.5 s and 1.56 GB, every one of
them written as an IMU-bridged ("degraded") pose with no IMU in the gap either, 7 km off on average after it, exit
0; now 788 updates, 6.6 s, 0.40 GB, exit 1 naming the gap, and after it 10.45 mm ATE (the uninterrupted run over the
same stretch 7.44 mm; before the gap unchanged, 12.00 mm). A 1 h gap (720 000 updates) was stopped after 150 s at
11.0 GB resident, about a tenth of the way (it could not have finished on this machine); now 5.5 s, 0.39 GB, the
same poses as the 60 s gap. ``evpose slam`` was not slowed by the gap (its windows follow the events: 17 s).

In the fused modes a stretch without IMU samples is a gap too (:func:`evpose.core.stream_gaps.merge_gaps` joins it with an event gap it
overlaps), and so is the end of a recording whose IMU stops before its events (the last update then says so, with
no restart). They were bridged by interpolating across the hole, or by holding the last sample: the demo ``landing``
with its IMU cut at 2 s wrote its last 2 s 0.68 m RMS off (2.5 m at most), exit 0, now 394 poses to 2.0 s (12.00 mm)
and exit 1 naming the IMU's end; with a 1 s hole from 1.5 s it was 4.4 m RMS off after the hole, now 17.4 mm.

Without ground truth (``--init``) the restart was from the last estimate with the velocity unknown, which is right
for a camera that stood still during the gap. In the splice above the camera moved on at 3.3 m/s, 0.1 m from the
last estimate when tracking restarted: the fusion did not catch up and wrote the 394 updates after the gap 3.45 m
RMS off (exit 1 for the gap). Tried and left out: reporting the fused modes' updates after a restart lost until the
map is acquired again (5 strict registrations in a row): it did not help there (a wrong lock 1.5 m off passed the
strict test, 78 of 759 points; still 4.2 m RMS over the 291 poses written) and cost the restart from ground truth
37 updates (12.92 against 10.45 mm). The polarity filter's hold for an unknown velocity is set again at such a
restart, as at a start without one (no change in that run).

Session 26 built a search for the pose for such a restart (:mod:`evpose.tracker.reacquisition`,
``reacquisition.enabled``, off by default): pose hypotheses around the last estimate, each tracked with the last
estimated velocity, the best accepted only with a chance-level z of 16 and 1.3 times the runner-up's; until then the
updates are lost, naming the search. The splice above is found again after 43 updates and written 13.6 mm RMS off (351
poses); where the camera flew on 0.2-1 s during the pause (0.7-2.5 m on, its velocity changed by 0.8-4.6 m/s) it is
not found and nothing is written after the gap (the restart from the last estimate: 3.0-3.8 m RMS off). But with the
pause at 1.0 / 1.5 / 3.0 s the restart from the last estimate recovers by itself (61 / 57 / 46 mm RMS after it) and the
search did worse (nothing written / a 44 mm lock that then drifted to 790 mm / nothing): hence off. A velocity that is
unknown, not the pose, is what kept the fusion off at 2 s: from the true pose with the velocity unknown it was 3.37 m
RMS off too.

Session 27 gates that restart (:class:`RestartGate`, ``TrackerConfig.restart_gate``, on by default): the updates after
a restart from the last estimate are reported lost, not written, until the median chance-level z
(:func:`~evpose.tracker.map_acquisition.chance_z`, an update without a registration counting 0) over the last 10
updates reaches 10; when that has not happened within 40 updates of the restart the gate gives it up and nothing is
written until the next restart. The tracker runs as without the gate (it changes only the reported status), so the
poses written are those of the ungated run from the update it passes on. Measured (``full``, from the first
ground-truth pose as ``--init``; the session-26 splices above and ten new ones made with
/tmp/s27/restart27/make_splice.py: RECORDING AT_S CUT_S PAUSE_S, ``L`` = ``landing``, ``F`` = ``landing_fast``, ``D`` =
``landing_dynamic``; per-update z and errors with the gate never passing, /tmp/s27/restart27/trace.py and trace2.py;
the gate applied offline, gate_sim2.py, exact because the gate does not change the tracker, confirmed by ``evpose
track`` on cut 0.2 s, pause at 1.5 s, ``D`` 1.5 s and ``L`` cut 0.05 s, check.sh, check2.sh; "delay": the update after
the restart that is written first; errors against each splice's own ground truth):

=====================  ==================================  ==================================
splice                 ungated (before): after the gap     gated (defaults): after the gap
=====================  ==================================  ==================================
pause at 2 s (60 s)    393 poses, 3456 mm RMS              nothing written
cut 0.2 / 0.5 / 1.0 s  353 / 293 / 193 poses, 3.0-3.8 m    nothing written
L cut 0.2 s at 1/3 s   553 / 153 poses, 8573 / 2589 mm     nothing written
L cut 0.05 s at 2 s    382 poses, 3165 mm                  nothing written
F cut 0.1 s at 1 s     273 poses, 3574 mm                  nothing written
D cut 0.2 s at 1.5 s   253 poses, 2506 mm                  nothing written
pause at 1.0 s         593 poses, 61 mm (2 > 0.1 m)        584 poses, 61 mm (1 > 0.1 m), delay 10
pause at 1.5 s         493 poses, 57 mm (2 > 0.1 m)        484 poses, 56 mm (0), delay 10
pause at 3.0 s         193 poses, 46 mm (5 > 0.1 m)        182 poses, 41 mm (0), delay 12
L pause at 0.5 s       693 poses, 39 mm (0)                684 poses, 38 mm (0), delay 10
F pause at 1.0 s       293 poses, 66 mm (1)                284 poses, 66 mm (0), delay 10
D pause at 1.5 s       293 poses, 64 mm (2)                264 poses, 63 mm (0), delay 30
L pause at 2.5 s       293 poses, 1319 mm (282 > 0.1 m)    284 poses, 1339 mm (282), delay 10
L pause at 3.5 s       93 poses, 2635 mm (90)              84 poses, 2772 mm (84), delay 10
=====================  ==================================  ==================================

(The 2 s pause of 60 s and of 2 s run the same updates after the gap. Runs from ground truth, and runs without a
gap, are not judged: the demo ``landing`` still hashes 469f53f67bcd8fbb, with ``--init`` 8d1b41529a489d37 as before.
In ``stpe`` and ``stpe+filter`` the restart from the last estimate recovered in none of the splices tried (pauses at
1.5 and 2 s, cut 0.2 s, ``F`` pause at 1 s: the tracker reports the updates lost itself, 0-6 written); the gate withholds
the 2 / 6 that ``stpe`` wrote, 383 / 273 mm RMS off. ``evpose track --smoothed`` writes no pose where the real-time
track is lost, so not the withheld stretch either (before this it wrote the 353 withheld updates of the cut
0.2 s splice, smoothed).)
Why a deadline and not a higher threshold: the chance-level z does not tell a wrong lock from a right restart by its
level. Median z over 10 updates where the pose is > 0.3 m off reaches 17.8 (pause at 2 s, the estimate 1-2 m off
and moving) and 18.9 (``L`` cut 0.05 s, 1.6-1.7 m off); where it is < 0.1 m off it is 0.0 / 14.6 / 24.3 (5th pct /
median / 95th pct; pause at 1.0 s), 0.0 / 15.4 / 24.4 (1.5 s), 12.3 / 16.2 / 24.8 (3.0 s), 0.0 / 11.9 / 18.8 (``D``):
right tracks have stretches without a registration (event-poor) and their best 10-update median in the first 60
updates is only 15.2-16.3 at the three held-out pauses. A threshold of 18 alone kept the pause at 2 s out (by 0.2
sigma) but cost the right restarts 72-149 updates, and ``L`` cut 0.05 s passed it (284 poses 3.6 m off); 16 let the
pause at 2 s through (289 poses, 4.0 m). What separates is *when*: a restart near the camera holds the map at once
(median z >= 10 at update 10-12, ``D`` 30), a wrong lock forms only after the estimate has wandered (update 49 at
``L`` cut 0.05 s, 61 at the pause at 2 s; the cuts never reach 10 over 10 updates, cut 0.2 s reaches 8 at update 34).
The deadline 40 sits between 30 and 49 (1.3x from either side; it was 30 before the ``D`` splice was measured, which
passed at exactly 30). Without the deadline (z >= 10 over 10) the pause at 2 s writes 333 poses 3.7 m off and ``L``
cut 0.05 s 334 poses 3.4 m off.

Not caught by the gate alone: ``L`` pauses at 2.5 and 3.5 s, where the camera stood still during the pause and the
restart starts right (40-50 mm off, z 22) and then drifts off at the camera's speed (the fused tracker restarted with
the velocity unknown: 0.24 m off after 32 updates, 2.3 m after 288 at 2.5 s); the gate judges only the start. A gate
that withdraws the track again when z falls would not separate either: the right ``D`` restart reads z 0 for 40 updates
at 0.07-0.08 m, while the drifting one still reads 19-21 at 0.13-0.18 m off.

Session 27 (helper vel27) gives that restart a velocity (``RestartGateConfig.carry_velocity``, on by default): in
``full`` the last estimate is carried on at the velocity last estimated before the gap over the event time since
it (:func:`carried_restart_pose`: the warm-up after the gap, 30 ms by default, less the time from the gap's last event
to that estimate; the gap itself is not bridged), and the fusion starts with that velocity as its prior (sigma
``fusion.init_sigma_velocity``, 0.5 m/s, the one a start from ground truth gets; no polarity hold). At a pause the last
velocity is the camera's within 0.05-0.18 m/s (``F``: 0.69); the carry moves the start 0.1 m at 3.3 m/s. Measured as
above (the same splices, ``full``, ``--init`` = the first ground-truth pose, gate at its defaults; the tracker traced
with the gate never passing and the gate applied offline, /tmp/s27/vel27/ev.py, on.log / off.log; confirmed by ``evpose
track`` on ``L`` 2.5 / 3.5 s, the pause at 2 s of 60 s and ``L`` cut 0.05 s, /tmp/s27/vel27/cli.sh, cli.log: 284 / 84 /
359 / 353 poses, 17.6 / 13.0 / 8.8 / 365 mm; ``--smoothed`` replays from the carried restart: ``L`` 2.5 s 284
smoothed poses 13.5 mm; "> 0.1": poses written more than 0.1 m off):

=====================  ========================================  ========================================
splice                 velocity unknown (before): after the gap  carried at the last velocity (default)
=====================  ========================================  ========================================
L pause at 2.5 s       284 poses, 1339 mm (282 > 0.1), delay 10  284 poses, 18 mm (0), delay 10
L pause at 3.5 s       84 poses, 2772 mm (84), delay 10          84 poses, 13 mm (0), delay 10
pause at 1.0 s         584 poses, 61 mm (1), delay 10            584 poses, 22 mm (0), delay 10
pause at 1.5 s         484 poses, 56 mm (0), delay 10            484 poses, 15 mm (0), delay 10
pause at 3.0 s         182 poses, 41 mm (0), delay 12            184 poses, 16 mm (0), delay 10
L pause at 0.5 s       684 poses, 38 mm (0), delay 10            684 poses, 16 mm (0), delay 10
F pause at 1.0 s       284 poses, 66 mm (0), delay 10            284 poses, 39 mm (0), delay 10
D pause at 1.5 s       264 poses, 63 mm (0), delay 30            260 poses, 27 mm (0), delay 34
pause at 2 s (60 s)    nothing written                           358 poses, 9 mm (0), delay 36
L cut 0.05 s at 2 s    nothing written (ungated 3165 mm)         352 poses, 368 mm (301), delay 31
the 7 other cuts       nothing written                           nothing written (ungated 0.53-3.6 m)
=====================  ========================================  ========================================

The one loss: ``L`` cut 0.05 s (0.16 m of flight cut, the velocity 0.29 m/s off) now passes the gate at update 31 at
0.13 m off, closes to 5 mm at update 66 and then drifts to 0.6 m by the end: 352 poses written 0.37 m RMS off where
nothing was. The gate cannot tell it from ``D`` (right, passes at 34). Runs from ground truth and ``stpe`` are unchanged
(the demo ``landing`` still hashes 469f53f67bcd8fbb, with ``--init`` 8d1b41529a489d37). Only ``full``: in
``stpe+filter`` (where the restart standing still writes nothing after the pauses at 1.5 / 2 s, ``F`` 1.0 s, ``L``
2.5 s, cut 0.2 s) the carried restart wrote the pause at 1.5 s 55 poses 934 mm RMS off and the others nothing (sf.log).
Also measured: the velocity prior alone (the pose not carried) recovers the two ``L`` pauses less well and costs the
others poses > 0.1 m (sigma 0.5: ``L`` 2.5 / 3.5 s 81 / 59 mm, 68 / 0 > 0.1; 1.0 / 1.5 / 3.0 s 60 / 56 / 46 mm, 8 / 26
/ 4 > 0.1; the 2 s pause passes at 41: withheld); sigma 1.0 does not hold the ``L`` pauses (425 / 371 mm), 0.25 costs
the 1.5 s pause 47 poses > 0.1 (lv*.log). A velocity fitted to the first registrations after the restart is no use
in ``full``: they start from the fusion's prediction and follow it (``L`` 2.5 s, velocity unknown: 40-90 mm off
over the first 10 updates, drifting with the fused pose), fits over 5-30 updates were 2.1-4.0 m/s off the truth
(/tmp/s27/vel27/trace_v.py, an.py).

Session 28 (helper restart28) measured the gate and the carry on 48 held-out splices, none used to choose them:
the three landing demos cut at other places with gaps of 1.5 / 5 / 60 s, the cached 3 s 346x260 ``landing`` (one turn;
seeds 30-41, one splice each) and ``indoor`` (seeds 0-5, with ``maps/indoor_map.ply``) recordings, and 3 s
``landing_rotation`` (90 deg/s yaw), ``landing_slow``, ``landing_noisy`` (seed 1; ``landing_texture`` was left out: it
did not simulate within 9 min). Splices are built in memory (SRC:AT_S:CUT_S:GAP_S; L / F / D demos, ``sl``/``si`` +
seed: the cache), run from the first ground-truth pose as ``--init``, the gate applied offline as in session 27 and
exact (/tmp/s28/restart28/ev28c.py, run_b.sh, c.log; the 17 session-27 splices rerun there give the figures of the
tables above; "uninterrupted": the same recording without the splice over the same stretch, base28.py):

=========================================================  =====================================================
held-out splices (session-27 defaults)                     after the gap
=========================================================  =====================================================
11 demo pauses (L 0.75-3.25, F 0.5-2.0, D 0.75 / 2.25 s)    all written from update 10, 11-45 mm RMS, none > 0.1 m
7 simulated landing pauses (5 seeds, slow, noisy)          all written from update 10 (seed 31: 26), 8-25 mm, none
``landing_rotation`` pause at 1.5 s                        267 poses, 72 mm (66 > 0.1 m), from update 27
                                                           (uninterrupted 8 mm)
indoor pauses at 1.0 / 1.5 / 2.0 s                         384 poses 136 mm (170) / withheld (ungated 141 mm) /
                                                           183 poses 113 mm (115); uninterrupted 33 / 38 / 42 mm
cuts of 0.02 s (L at 2 s, F at 0.5 s, seed 39 at 1.8 s)    351 poses 23 mm (0), from update 39 / 377, 50 mm (3) /
                                                           withheld (ungated 67 mm, 29 > 0.1)
23 cuts of 0.05-0.3 s (demos, 9 simulated, 3 indoor)       all withheld but L cut 0.1 s at 2 s: 347 poses, 451 mm
                                                           (297 > 0.1), from update 27
=========================================================  =====================================================

So the deadline and the threshold do not hold up as a separation: a second wrong lock (next to the known one, L cut
0.05 s at 2 s) passes at update 27 with a median z of 10.3, while a right restart (L cut 0.02 s at 2 s) passes at 39,
one update inside the deadline; right restarts pass at median z 10.2-25.8. What the gate still does: of the 26
held-out cuts it withholds 23 (the two wrong locks are cuts at the same corner of the demo's spiral). Where the restart
starts right and then drifts (``landing_rotation``, indoor) the gate cannot see it, as for the session-27 pauses before
the carry. Other rules over all 65 splices (rules.py; poses > 0.1 m written, session-27 defaults 952 in 6 splices):
a deadline of 25 withholds both wrong locks (288 in 3) but also three right pauses (``D`` 1.5 s, ``L`` 2 s, seed 31)
and the rotation pause; 60 lets five more cuts through (1550 in 11), 80 with all 10 updates registered 1905 in 12;
requiring 9 or 10 of the 10 updates registered changes nothing else (945 / 942); a median z of 12 withholds the
two drifting pauses (rotation, indoor 2.0 s) and the right ``L`` 2.75 s one but neither wrong lock (765 in 4); 14
within 60 also seed 31's pause and lets ``L`` cut 0.1 s at 3.5 s through (776 in 5).
Why the cuts at 2 s lock: no update registers for the first 21-26 (the fused pose is the IMU dead reckoning from the
carried restart); the first registrations, 0.13 / 0.28 m off, pull the pose to within 5-25 mm by update 60-90 while
the fused velocity's error grows from 0.3-0.45 to 0.7 m/s along the flight before the corner, and the estimate then
drifts off at that rate (0.6 m by the end): the registrations there do not hold the translation along it and follow the
fusion's prediction. The right pause at the same place (2 s, 60 s) starts registering at update 31 and passes at 36.
Tried as a discriminator at the gate's pass (the 10 judged updates; the 2 wrong locks against the 28 right restarts of
both sets, disc2.py, disc3.py, disc3_c.txt); none separates: the fused position's distance from an IMU-only dead
reckoning from the carried restart (``ImuOnlyPropagator``; wrong locks 0.011-0.021 m, right restarts 0.002-0.042 m:
the ``F`` pauses' carried velocity is 0.7-0.9 m/s off, so their dead reckoning parts faster than a cut's slow pull; a
0.05 m limit withholds neither wrong lock); the registration
counts (wrong / right: inliers per used point 0.041-0.045 / 0.035-0.31, both-polarity points 0.71 / 0.27-0.74,
wrong-polarity events 0.09-0.12 / 0.007-0.37, events removed by polarity 0.36-0.42 / 0.09-0.70, updates registered
6-7 / 6-10 of 10, chance hits 0.008-0.013 / 0.008-0.15: the right pause at 2 s reads like the wrong locks); the fused
accelerometer bias (a tilt mode: it stays < 0.14 m/s^2); the fused covariance (ev28f.py: largest translation sd 50-57
mm for the wrong locks, 52-67 mm for the right restarts that pass late, the two at the same corner, ``D`` 1.5 s and
seed 31, 14-17 mm for those passing at update 10; weakest along the flight at the corner, right and wrong alike).
The velocity error would (0.42-0.54 m/s against <= 0.2 for the pauses) but is not observable, and the right 0.02 s cut
has 0.37. Nor does a wider position prior for the restarted fusion let the registrations move the pose without
bending the velocity (``fusion.init_sigma_trans`` 0.1 m instead of 0.01 at such restarts only, ev28e.py SIGT=0.1: L cuts
at 2 s 0.05 / 0.1 s 495 / 604 mm instead of 368 / 451, F cut 0.05 s at 1.5 s now passes, 176 mm; the pauses 12-39 mm,
9-39 before).

What made the held-out right-then-drifting restarts drift, measured as options (off by default):
``carry_biases`` (the fusion restarted from zero biases; indoor the accelerometer's 0.1 m/s^2 drove the velocity 0.2 m/s
off over 1.5 s of few registrations) and ``carry_rotation`` (the carried pose kept the last orientation over the
warm-up: 3.4 deg off at 90 deg/s). Both sets, the gate at its defaults (bb.log + bo.log, new.log; summary.py):

============================  ============================  ============================  ============================
                              session-27 defaults           ``carry_biases``              ``carry_biases`` +
                                                                                          ``carry_rotation``
============================  ============================  ============================  ============================
old 17: writing > 0.1 m       1 splice (301 poses)          1 (301; L cut 0.05 s 360 mm)  2 (592: + L cut 0.2 s, 844 mm)
old 17: the 9 pauses          RMS 9-39 mm, median 16        7-35 mm, median 12            8-36 mm, median 10
held-out: writing > 0.1 m     5 splices (651 poses)         5 (527)                       7 (1428)
held-out: the 22 pauses       21 written, median 19 mm      20 written, median 16 mm      22 written, median 13 mm
============================  ============================  ============================  ============================

``carry_biases`` mends the indoor pause at 1.0 s (136 -> 44 mm, 170 -> 0 poses > 0.1 m) and makes 8 of 9 old pauses
more accurate (L 2.5 s 18 -> 7 mm), but the rotation pause is now withheld (72 mm before) and two more cuts pass: F cut
0.05 s at 1.5 s (149 poses 171 mm, 88 > 0.1) and seed 39 cut 0.02 s (190 poses, 61 mm, 23 > 0.1, passing at 39). With
``carry_rotation`` the rotation pause is written 5 mm RMS from update 10 and indoor 2.0 s 113 -> 43 mm, but four more
cuts than with the session-27 defaults lock wrongly (L 0.6 s 743 mm, L 3.0 s 119 mm, F 1.5 s, and the old L cut 0.2 s,
844 mm from update 16) and indoor 1.0 s is 146 mm again. A better restart also lets more cuts through the gate:
neither is on by default until a discriminator exists (runs from ground truth and without a gap are unaffected either
way: demo ``landing`` 469f53f67bcd8fbb, with ``--init`` 8d1b41529a489d37, and ``evpose track --init`` on ``L`` 2.5 s
writes session 27's output byte for byte, final28.sh; with ``--config`` ``carry_biases: true``: indoor 1.0 s 384 poses
43.5 mm, F cut 0.05 s 149 poses 170.5 mm (88 > 0.1 m), ``L`` 2.5 s 284 poses 7.4 mm, clibias.sh; cli28.sh: the
defaults, 136.0 / withheld / 17.5 mm).

:class:`UpdateSchedule` maps the session's update count to grid indices and back in O(log gaps): the cost of a gap
no longer depends on its length.
"""

from __future__ import annotations

import bisect
import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.stream_gaps import EventGap
from evpose.tracker.map_acquisition import chance_z, registered
from evpose.tracker.step_result import StepResult, TrackStatus

if TYPE_CHECKING:
    from evpose.core.camera import CameraCalibration
    from evpose.core.imu import ImuSamples

DEFAULT_MAX_EVENT_GAP_MS = 1000.0
"""``TrackerConfig.max_event_gap_ms``'s default (here so that ``evpose info`` can name it without importing the tracker)."""


class UpdateSchedule:
    """Grid index per update of a session whose events end at ``t_end_us``: update ``u`` (1-based) is at
    ``t0 + grid(u) * dt``. Updates run in segments of consecutive grid indices; the first update of every segment
    but one starting at grid index 1 is a gap's update (:meth:`gap_of`)."""

    def __init__(self, gaps: list[EventGap], t0_us: int, dt_us: int, t_end_us: int, warmup_us: int):
        last = max((int(t_end_us) - int(t0_us)) // int(dt_us), 0)
        starts: list[int] = []
        ends: list[int] = []
        jumps: list[EventGap | None] = []
        start, jump = 1, None
        for g in gaps:
            k_last = max((g.t_last_us - t0_us) // dt_us + 1, 0)  # the update that takes the gap's last event
            k_restart = min(-((t0_us - g.t_next_us - warmup_us) // dt_us), last)
            if k_restart <= k_last + 1 or k_restart < start:
                continue  # no update to skip (a coarse grid), or past the end
            if k_last < start:
                # The events between the previous gap and this one end before the previous restart: one update
                # stands for both gaps.
                jump = EventGap(jump.t_last_us if jump is not None else g.t_last_us, g.t_next_us,
                                g.stream if jump is None or jump.stream == g.stream else "events or IMU samples")
            else:
                starts.append(start), ends.append(k_last), jumps.append(jump)
                jump = g
            start = k_restart
        if start <= last:
            starts.append(start), ends.append(last), jumps.append(jump)
        keep = [i for i in range(len(starts)) if ends[i] >= starts[i]]
        self._k0 = np.array([starts[i] for i in keep], dtype=np.int64)
        lengths = np.array([ends[i] - starts[i] + 1 for i in keep], dtype=np.int64)
        self._u0 = np.concatenate([[1], 1 + np.cumsum(lengths)[:-1]]).astype(np.int64) if keep else np.zeros(0, np.int64)
        self._len = lengths
        self._gaps = [jumps[i] for i in keep]
        self._u0_list = [int(v) for v in self._u0]
        self._k0_list = [int(v) for v in self._k0]
        """The segments' first updates and grid indices as Python ints: every update looks them up two or three times,
        and ``bisect`` on a short list costs ~0.3 us against ~2 us for ``np.searchsorted`` and its scalar conversions."""
        self.total = int(lengths.sum())
        """Number of updates a full run makes."""

    @property
    def gaps(self) -> list[EventGap]:
        """The gaps one update each stands for, in time order."""
        return [g for g in self._gaps if g is not None]

    def grid(self, u: int) -> int:
        """Grid index of update ``u`` (1-based; 0 -> 0, the start)."""
        if u <= 0 or not self.total:
            return 0
        s = bisect.bisect_right(self._u0_list, u) - 1  # np.searchsorted(self._u0, u, side="right") - 1
        return int(self._k0_list[s] + (u - self._u0_list[s]))

    def gap_of(self, u: int) -> EventGap | None:
        """The gap update ``u`` stands for, None for a regular update."""
        if u <= 0 or u > self.total:
            return None
        s = bisect.bisect_right(self._u0_list, u) - 1
        return self._gaps[s] if u == self._u0_list[s] else None

    def updates_until(self, k: int) -> int:
        """How many updates lie at grid index ``k`` or before."""
        s = int(np.searchsorted(self._k0, k, side="right")) - 1
        if s < 0:
            return 0
        return int(self._u0[s] + min(k - self._k0[s], self._len[s] - 1))


@dataclass
class RestartGateConfig:
    """The chance-level gate on a restart without ground truth (:class:`RestartGate`)."""

    min_chance_z: float = field(default=10.0, metadata={"min": 0.0, "max": 100.0, "step": 0.5, "unit": "sigma"})
    """After a restart from the last estimate (an event gap, no ground truth, no re-acquisition search), updates are
    reported lost, not written, until the median chance-level z (:func:`~evpose.tracker.map_acquisition.chance_z`;
    an update that did not register counts 0) over the last ``run_updates`` reaches this, binomial standard deviations
    (0 = off: every update after the restart is written as tracked, as before session 27). Landing demo splices (module
    docstring): right restarts reach 10 at update 10-30, the cuts (0.7-8.6 m off) never; wrong locks later (49, 61).
    Held-out splices (session 28): right restarts pass at median z 10.2-25.8, a wrong lock at 10.3."""
    run_updates: int = field(default=10, metadata={"min": 1, "max": 1000, "step": 1, "unit": "updates"})
    """Updates whose median z the gate judges (0.05 s at 200 Hz), updates."""
    carry_velocity: bool = True
    """Restart ``full`` from the last estimate carried on at the velocity last estimated before the gap, over
    the event time since that estimate (the gap itself excluded: :func:`carried_restart_pose`), with that velocity as
    the fusion's prior (sigma ``fusion.init_sigma_velocity``, 0.5 m/s; no polarity hold), not standing still with the
    velocity unknown (False: as before). Landing demo splices (module docstring, session 27): the pauses 9-39 mm RMS
    after the gap, 0 poses > 0.1 m, where standing still they were 38-66 mm, 1.3 / 2.8 m off (``L`` 2.5 / 3.5 s) and
    withheld (2 s); but the 0.05 s cut is now written 0.37 m RMS off (withheld before). The other modes (in
    ``stpe+filter`` it wrote the pause at 1.5 s 0.93 m off) and restarts from ground truth are unaffected."""
    carry_biases: bool = False
    """With ``carry_velocity``: the restarted fusion starts from the accelerometer and gyroscope biases it estimated
    before the gap (prior sigma ``fusion.init_sigma_acc_bias`` / ``init_sigma_gyro_bias`` around them), not from zero as
    at a session's start (False). Off: on the held-out splices (module docstring, session 28) it mends the indoor pause
    that drifted 136 mm RMS off (44 mm) and makes 8 of the 9 old pauses more accurate (median 16 -> 12 mm), but the
    ``landing_rotation`` pause is withheld and two more cuts pass the gate (171 / 61 mm RMS, 88 / 23 poses > 0.1 m)."""
    carry_rotation: bool = False
    """With ``carry_velocity``: the carried pose is also turned by the gyroscope's mean rate over the warm-up after the
    gap (less the last gyroscope bias estimate), over the same event time as it is moved (False: its orientation is the
    last estimate's). Off: with ``carry_biases`` on the held-out splices (module docstring, session 28) it writes the
    ``landing_rotation`` pause 5 mm RMS (72 mm before) but four more cuts pass the gate as wrong locks (0.12-0.84 m
    RMS)."""
    deadline_updates: int = field(default=40, metadata={"min": 0, "max": 100000, "step": 1, "unit": "updates"})
    """The gate gives the restart up when the evidence has not passed within this many updates after it: every later
    update is lost until the next restart (0 = it waits to the end), updates. Landing demo splices: right restarts pass
    at update 10-30, wrong locks at 49 and 61 (0.98 / 1.07 m off then, 3.4 / 3.7 m RMS afterwards); 40 between. Not
    confirmed on the 48 held-out splices of session 28: a wrong lock passes at 27 (451 mm RMS after it), a right restart
    at 39; the deadline separates nothing there, the chance level withholds 23 of 26 cuts."""


def carried_restart_pose(pose: np.ndarray, velocity: np.ndarray, gap: EventGap, t_estimate_us: int, until_us: int,
                         angular_velocity_cam: np.ndarray | None = None) -> np.ndarray:
    """``pose`` (the last estimate, at ``t_estimate_us``) moved on at ``velocity`` (world, m/s) to the restart at
    ``until_us``, over the event time only: from the estimate to the gap's last event (<= 0: the estimate is the update
    after it) and from the first event after the gap to the restart (the warm-up). The gap itself is not bridged: how
    the camera moved then is unknown (a recorder paused while it stood still, or flew on: the cuts).
    ``angular_velocity_cam`` (rad/s, camera frame; None: not turned) turns it over the same time."""
    moved_s = ((int(until_us) - int(gap.t_next_us)) + min(int(gap.t_last_us) - int(t_estimate_us), 0)) * 1e-6
    out = np.array(pose, dtype=np.float64, copy=True)
    out[:3, 3] += np.asarray(velocity, dtype=np.float64).reshape(3) * moved_s
    if angular_velocity_cam is not None and moved_s > 0:
        turn = Rotation.from_rotvec(np.asarray(angular_velocity_cam, np.float64).reshape(3) * moved_s)
        out[:3, :3] = out[:3, :3] @ turn.as_matrix()
    return out


def warmup_angular_velocity(imu: ImuSamples | None, gap: EventGap, until_us: int, calibration: CameraCalibration,
                            gyro_bias: np.ndarray | None) -> np.ndarray | None:
    """The camera's mean angular velocity (rad/s, camera frame) over the warm-up after ``gap`` (its first event to the
    restart at ``until_us``) from the gyroscope samples in ``imu`` less ``gyro_bias`` (IMU frame); None without a
    sample."""
    if imu is None:
        return None
    off = int(calibration.time_offset_us)
    w = imu.time_window(int(gap.t_next_us) + off, int(until_us) + off)
    if not len(w):
        return None
    gyro = w.gyro.mean(axis=0) - (0.0 if gyro_bias is None else np.asarray(gyro_bias, np.float64).reshape(3))
    return np.asarray(calibration.T_cam_imu, np.float64)[:3, :3] @ gyro


class RestartGate:
    """Withholds the updates after a restart without ground truth until the map's chance-level evidence is back.

    The tracker runs as without it (only the reported status changes), so the poses once it passes are those of the
    ungated run."""

    def __init__(self, config: RestartGateConfig):
        self.config = config
        self.z: list[float] = []
        """Chance-level z of every update judged so far."""
        self.passed = False
        self.given_up = False
        """The evidence did not pass within ``deadline_updates``: nothing more is written after this restart."""

    def judge(self, result: StepResult) -> StepResult:
        """``result`` as it is once the evidence passed (this update included), else a lost copy saying why."""
        own = f"the tracker's own status: {result.status.value}{': ' + result.reason if result.reason else ''}"
        deadline = int(self.config.deadline_updates)
        if self.given_up:
            return dataclasses.replace(result, status=TrackStatus.LOST, reason=(
                f"after the restart from the last estimate the map was not acquired again within {deadline} updates:"
                f" nothing is written until the next restart ({own})"))
        z = chance_z(result.counts) if registered(result.counts) else None
        self.z.append(0.0 if z is None else float(z))
        n = max(int(self.config.run_updates), 1)
        med = float(np.median(self.z[-n:]))
        if len(self.z) >= n and med >= float(self.config.min_chance_z):
            self.passed = True
            return result
        self.given_up = 0 < deadline <= len(self.z)
        return dataclasses.replace(result, status=TrackStatus.LOST, reason=(
            f"after the restart from the last estimate the map is not acquired again yet (median chance-level z"
            f" {med:.1f} over the last {min(len(self.z), n)} updates, need {float(self.config.min_chance_z):g} over"
            f" {n}{f' within {deadline}' if deadline > 0 else ''}; {own})"))

    def snapshot(self) -> tuple[list[float], bool, bool]:
        return list(self.z), self.passed, self.given_up

    @classmethod
    def restored(cls, config: RestartGateConfig, state: tuple[list[float], bool, bool]) -> RestartGate:
        gate = cls(config)
        gate.z, gate.passed, gate.given_up = list(state[0]), bool(state[1]), bool(state[2])
        return gate
