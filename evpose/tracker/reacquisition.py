"""Re-acquisition search: find the pose again when the tracker restarts without knowing where the camera is.

After a long event gap a session that did not start from ground truth would restart from the last estimate
(:mod:`evpose.tracker.event_gaps`), but the camera has moved on meanwhile, and the fused modes need its velocity too.
With this search on (``TrackerConfig.reacquisition.enabled``, off by default: see the held-out figures below) the
tracker does not restart there but runs **trials**: from a
set of pose hypotheses around the pose it would restart from (translations across the optical axis of that pose, every
``grid_step_px`` of image motion at the visible map's median depth, out to a radius of ``speed_m_s`` times the time since
the last estimate, at most ``max_radius_m``; rotations about the optical axis every ``yaw_step_deg`` out to
``yaw_range_deg``; nearest first, at most ``max_hypotheses``), each with the velocity the tracker last estimated, the
whole tracker (fusion, polarity filter, registration) is started and stepped on
the same events for ``trial_updates`` updates, its state kept apart (snapshots). Each trial's evidence is the median
chance-level z (:func:`~evpose.tracker.map_acquisition.chance_z`) of its registrations; after ``prune_after`` updates
only the ``keep_trials`` best go on. At the end of a round the best trial is accepted only if its evidence reaches
``min_z``, its median inlier share ``min_inlier_share``, and it beats the best trial that ended elsewhere (``distinct_px``
of image motion away) ``margin`` times over; the tracker then goes on from that trial's state. Otherwise the next update
starts a new round (wider: the radius follows the elapsed time). Every update of a round is reported lost, with a
reason naming the search and its figures.

The work per update is bounded by counts, not clocks (a time budget would make the output depend on the machine):
at most ``max_hypotheses`` tracker updates (then ``keep_trials`` and the centre's), each with a snapshot and a restore.
Updates in which no trial registers (an event-poor stretch) do not count towards the round; after
``max_idle_updates`` of them, or a round without an accepted trial, the next round is centred on the centre's trial
(the last estimate carried on by the IMU with the last velocity). A session without such a restart never starts the
search: its output is bit for bit what it was (the demo ``landing`` from ground truth still hashes 469f53f67bcd8fbb;
simulated landing seed 0 and indoor seed 1, 1 s at 240x180, ``full`` and ``stpe``: the same poses as before,
/tmp/s26/reloc26/simcheck.py). Memory: a session snapshot taken during a search holds every trial's tracker state
(~4.4 MB each at 346x260 in ``full``: ~110 MB with the default 25), shared, not copied, with the running search.

Measured (session 26, ``evpose track demo_data/landing.h5``-derived splices with ``--init`` = the first ground-truth
pose, ``full`` mode; /tmp/s26/reloc26/make_gap.py = /tmp/s25/cli25/make_gap.py: everything after 2 s moved GAP s later,
so the camera is 0.1 m past the last estimate at the restart (3.3 m/s over the 30 ms warm-up), at its velocity;
make_cut.py: CUT s of flight after 2 s cut out and a 1.5 s pause put in, so it is 0.71 / 1.45 / 2.51 m past it and its
velocity changed by 0.8 / 2.2 / 4.6 m/s (the landing path turns); ``measure.sh TAG CONFIG``, analyze.py; "off" =
``reacquisition.enabled: false`` (off.yaml), the default and what ran before; "search" = on.yaml, the other settings
at their defaults; CPU = thread time of a search update, median / max, within ~20 % from run to run on the shared
machine; the ``stpe`` row: the splice without IMU, ``--mode stpe``):

===============  ===========================  ===========================================================  ==========
splice           off: after the gap           search                                                      CPU (ms)
===============  ===========================  ===========================================================  ==========
gap 60 s / 2 s   393 poses, 3456 mm RMS off   found after 43 updates, 351 poses, 13.6 mm RMS (max 23)     117 / 137
cut 0.2 s        353 poses, 3046 mm RMS off   not found: 353 updates lost, no pose written                29 / 194
cut 0.5 s        293 poses, 3002 mm RMS off   not found: 293 lost, none written                           117 / 320
cut 1.0 s        193 poses, 3841 mm RMS off   not found: 193 lost, none written                           136 / 300
gap 60 s, stpe   none written (lost)          none written (rounds at best z 5-10)                        16 / 123
===============  ===========================  ===========================================================  ==========

(The restart from ground truth over the same gap: 10.45 mm. ``--smoothed`` replays from the accepted trial's pose and
velocity: gap 60 s, 7.13 mm RMS over the 351 smoothed poses after the gap. ``evpose eval --align none`` over the whole
run, gap 60 s:
2433 -> 14.4 mm RMS, 793 -> 751 poses; cuts 0.2 / 0.5 / 1.0 s: 2086 / 1952 / 2191 mm RMS over 753 / 693 / 593
poses -> 15.1 mm over the 400 before the gap. Exit 1 either
way: the gap's update is lost.) No wrong pose was accepted in any round (poses written >0.1 m off: 0). In the gap splice
the first 27 updates after the restart register nowhere, even from the true pose and velocity (an event-poor stretch,
~250 events per 5 ms): the round waits them out; the trials then register with z ~20 against the others' 0-13.

Held out (the same splice with the pause at 1.0 / 1.5 / 3.0 s instead of 2 s, /tmp/s26/reloc26/make_gap_at.py): there
the old restart recovers by itself, 61.0 / 56.7 / 46.2 mm RMS after the gap (max 114-126 mm, 2-5 poses > 0.1 m off).
The search wrote nothing after the gap at 1.0 and 3.0 s (every round refused: the best trials, 41-380 mm off, read
z 11-21 with distinct runners-up within 1.3x; the hypotheses converge to several nearby poses when events are dense),
and at 1.5 s accepted a trial 44 mm off after 91 updates whose track then lost its registrations (2-36 inliers of ~730)
and drifted to 790 mm RMS (914 mm, 5.3 m max, written as degraded): the last estimated velocity the trials started with
was 1.0 m/s off the truth, the accepted trial's still 0.58 m/s at acceptance (the limit found below). Adding the old restart itself (the centre, velocity
unknown, polarity hold) as one more trial did not help: nothing written at any of the three (it does not converge within
a round's 10 registered updates). So the search is off by default: it is a better answer only where the old restart
fails outright, and it does not tell the two cases apart. (Since session 27 the old restart carries the last estimate
on at the last velocity, ``restart_gate.carry_velocity``: the gap splice 9 mm RMS after the gap, the held-out pauses
15-22 mm; the cuts are still not found, :mod:`evpose.tracker.event_gaps`.) (Session 27 gates the old restart instead,
:class:`~evpose.tracker.event_gaps.RestartGate`: of the splices above it writes nothing after the gap where the
old restart was metres off, and the held-out pauses 9-11 updates later, 56-61 / 41 mm RMS.)

Why the cuts are not found: the velocity. A trial started from the true pose with the true velocity (a debugging trial,
/tmp/s26/reloc26/judge_dbg.py ``TRUTH_TRIAL=1``) is accepted in the first round of cut 0.2 s with z 18.5 while every
hypothesis reads 0; with the velocity 0.5 m/s off (either horizontal axis, or vertical) it is still accepted (z 18.2-19.4)
and tracks on at 12.5-13.0 mm; 1 m/s off it is accepted 45 mm off and then diverges (966 mm RMS): so the velocity must be
known within ~0.5 m/s, and a search over velocity too (the landing path turns at constant speed: the velocity rotated about
gravity would be the natural family) multiplies the trials by the number of velocities, at ~5 ms each; and where that
was tried (below) the trials that came close were not told apart from those 0.2-0.35 m off.

Tried and left out:

- Registering each hypothesis once on a field blurred 11 px and then on the tracker's field, both of the combined
  polarity, and scoring the result's chance-level z (the single-update search of the brief): after the gap the map's
  evidence in one update is too weak. At the true pose the combined field reads z 0.9-2.9 (inlier share 0.01-0.02) in
  the first updates, 1.8-7.2 with the time surface's decay lengthened to 20-80 ms, and registering from the true pose
  moves it 40-340 mm; before the gap, 14.1 / 9.3 (updates 100 / 390). The fused tracker registers only because the
  polarity filter's ``T_align`` gathers the events of the predicted motion (/tmp/s26/reloc26/probe2.py).
- Judging the trials on that combined field at their poses instead of by their own registrations: the true pose reads
  z 6-13 where trials 0.27-0.69 m off read 11-16 (cut 0.2 s, /tmp/s26/reloc26/judge_dbg.py), and the gap splice was not
  found any more (the best trials, 50-220 mm off, read 8-17.5 and never cleared the margin). A trial's own
  chance-level z can flatter it (``T_align`` shows only the events near its predicted points), but trials that do not
  hold the map do not register at all (z 0): that is what separates them.
- Restarting the trials from the last estimate without a velocity (as before, polarity hold): from the true pose with
  the velocity unknown the fused tracker stays put and drifts off at the camera's speed (3.37 m RMS after the gap, the
  same failure as from the last estimate, 3.46 m): the restart's problem was the velocity more than the pose. The last
  estimate with the true velocity alone gives 53.8 mm, with the last velocity 41.3 mm (gap splice; cuts 0.70-3.63 m).
- Hypotheses along the optical axis too (every 3 lateral steps; box scene of ``tests/tracker``, ``stpe``): a trial
  0.2 m off in depth was accepted at z 18 and stayed 0.3 m off; lateral ones only, the trial accepted ~0.1 m off in
  depth converges to < 10 mm within 15 updates.
- More hypotheses for the cuts: cut 0.2 s with ``max_hypotheses`` 169 (radius ~0.77 m, the truth 0.71 m away) ran 10
  rounds without acceptance: the best trials stayed 230-550 mm off at z 8-18.4, each refused by the margin (the
  runner-up at 11.5-16.5); 169 tracker updates per update until the round's third registered one (~1 s of CPU at
  the ~5.8 ms per trial and update the defaults show: 144 ms for 25; an ordinary update costs ~3.8 ms).
- Hypotheses along the last velocity (the camera flew on: every grid step out to 1 m ahead, one step either side
  across it, horizontally) with the velocity also turned 15 deg either way about gravity (the landing path turns), 90-99
  trials a round (cut 0.2 s, /tmp/s26/reloc26/line_exp.py): trials came within 35-50 mm of the truth, but read z 16.8-17.0
  where trials 0.16-0.35 m off read 18-20; every round was refused (a distinct runner-up within the margin, or the best
  below ``min_z``). Over these updates the evidence does not tell a pose 40 mm off from one 0.2 m off, so more
  hypotheses alone do not find the cuts.
- Trials with the camera at rest besides the last velocity: no splice here needs them, and they double the work.
- The old restart as one more trial (above, held out): nothing written at 1.0 / 1.5 / 3.0 s.
- The fused modes "lost for K updates" as a trigger: not built. In the fused modes a track is never reported lost,
  and an event-poor stretch (27 updates without a registration after the gap even from the truth) looks the same as a
  lost track while the IMU carries the pose well.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import gtsam
import numpy as np

from evpose.tracker.map_acquisition import chance_z
from evpose.tracker.step_result import StepResult, TrackStatus
from evpose.tracker.visible_map import visible_points

if TYPE_CHECKING:
    from evpose.core.events import EventArray
    from evpose.core.imu import ImuSamples
    from evpose.tracker.tracker import Tracker


@dataclass
class ReacquisitionConfig:
    """The re-acquisition search (:mod:`evpose.tracker.reacquisition`)."""

    enabled: bool = False
    """Search for the pose when the tracker restarts without ground truth after an event gap, instead of restarting
    from the last estimate with the velocity unknown. Off: where that restart recovers by itself (the demo's gap moved
    to 1.0 / 1.5 / 3.0 s: 61 / 57 / 46 mm RMS after it) the search wrote nothing / lost the accepted track (790 mm) /
    wrote nothing; it wins only where the old restart fails (the gap at 2 s: 3456 -> 13.6 mm). See the module docstring."""
    speed_m_s: float = field(default=5.0, metadata={"min": 0.0, "max": 100.0, "step": 0.1, "unit": "m/s"})
    """Fastest the camera is assumed to move while untracked: the search radius is this times the time since the last
    estimate (at least one grid step), metres per second."""
    max_radius_m: float = field(default=1.0, metadata={"min": 0.0, "max": 100.0, "step": 0.05, "unit": "m"})
    """Largest translation searched from the pose the tracker would restart from, metres."""
    grid_step_px: float = field(default=5.0, metadata={"min": 0.5, "max": 100.0, "step": 0.5, "unit": "px"})
    """Spacing of the translation hypotheses as image motion at the visible map's median depth, pixels."""
    max_hypotheses: int = field(default=25, metadata={"min": 1, "max": 1000, "step": 1, "unit": "hypotheses"})
    """Pose hypotheses per round, the nearest first (each a tracker update per update: bounds the work), hypotheses."""
    yaw_range_deg: float = field(default=0.0, metadata={"min": 0.0, "max": 180.0, "step": 1.0, "unit": "deg"})
    """Rotations about the optical axis searched either side of the restart pose's, degrees (0 = that rotation only)."""
    yaw_step_deg: float = field(default=10.0, metadata={"min": 1.0, "max": 90.0, "step": 1.0, "unit": "deg"})
    """Spacing of the rotation hypotheses about the optical axis, degrees."""
    trial_updates: int = field(default=10, metadata={"min": 1, "max": 200, "step": 1, "unit": "updates"})
    """Updates each trial runs before the round is judged, updates."""
    max_idle_updates: int = field(default=60, metadata={"min": 1, "max": 10000, "step": 1, "unit": "updates"})
    """A round in which no trial registers for this many updates starts over around the best trial's propagated
    pose, updates."""
    prune_after: int = field(default=3, metadata={"min": 1, "max": 200, "step": 1, "unit": "updates"})
    """After this many updates of a round only the ``keep_trials`` best trials go on, updates."""
    keep_trials: int = field(default=5, metadata={"min": 2, "max": 1000, "step": 1, "unit": "trials"})
    """Trials kept after ``prune_after`` updates (at least two: the runner-up is the margin's measure), trials."""
    min_z: float = field(default=16.0, metadata={"min": 0.0, "max": 200.0, "step": 0.5, "unit": "sigma"})
    """Least median chance-level z (:func:`~evpose.tracker.map_acquisition.chance_z`) of an accepted trial's
    registrations, binomial standard deviations (the acquisition window's ``min_chance_z``). Landing demo splices: the
    trial that holds the map 18.5-19.6, the others 0-13; but trials 0.23-0.55 m off reached 16-18.4 where none held it
    (cut 0.2 s): the margin, not this, refused them."""
    min_inlier_share: float = field(default=0.05, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """Least median share of the map points in the image that lie on recent events in an accepted trial, ratio (the
    fused modes' ``fused_min_inlier_ratio``)."""
    margin: float = field(default=1.3, metadata={"min": 1.0, "max": 10.0, "step": 0.05, "unit": "ratio"})
    """The best trial's evidence must be this many times that of the best trial that ended elsewhere, ratio. Landing
    demo splices (module docstring): the wrong trials that reached ``min_z`` led their runners-up by 1.00-1.14x (cut
    0.2 s with 25 and with 169 hypotheses), the right one of the gap splice by 1.51x (z 19.6 against 13.0, a trial 0.18 m
    off); 1.3 is about their geometric mean (1.5 took the same decisions there, one of them by 0.01)."""
    distinct_px: float = field(default=4.0, metadata={"min": 0.5, "max": 100.0, "step": 0.5, "unit": "px"})
    """Two trials ended in the same pose when the map's image moves less than this between them, pixels."""


@dataclass
class _Trial:
    """One pose hypothesis run through the tracker."""

    start: np.ndarray
    velocity: np.ndarray | None
    state: dict | None = None
    """The tracker's state after the trial's last update (a snapshot)."""
    z: list = dataclasses.field(default_factory=list)
    share: list = dataclasses.field(default_factory=list)
    result: StepResult | None = None
    centre: bool = False
    """The trial from the round's centre (kept to the end of the round: it carries the next round's centre)."""

    def evidence(self) -> tuple[float, float]:
        """(median z, median inlier share) so far; updates without a registration count 0."""
        if not self.z:
            return 0.0, 0.0
        return float(np.median(self.z)), float(np.median(self.share))


@dataclass
class _State:
    """What the search carries from one update to the next."""

    center: np.ndarray
    """The pose the tracker would have restarted from (4, 4)."""
    t_center_us: int
    """Time of that pose (the last estimate), microseconds."""
    velocity: np.ndarray | None
    """The last estimated world velocity (m/s), None when the tracker had none."""
    reason: str
    """Why the search runs (the gap's words)."""
    trials: list = dataclasses.field(default_factory=list)
    updates: int = 0
    """Updates of the current round so far."""
    rounds: int = 0
    """Rounds ended without an accepted trial."""
    idle: int = 0
    """Updates of the current round in which no trial registered."""


def _rz(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def _median_depth(tracker: Tracker, pose: np.ndarray) -> float:
    idx = visible_points(tracker._points, pose, tracker.K, tracker.width, tracker.height, tracker.config.visible_map)
    if not idx.size:
        return 1.0
    return max(float(np.median(((np.take(tracker._points, idx, axis=0) - pose[:3, 3]) @ pose[:3, :3])[:, 2])), 1e-3)


def hypotheses(config: ReacquisitionConfig, center: np.ndarray, depth_m: float, focal_px: float, elapsed_s: float) -> np.ndarray:
    """(H, 4, 4) pose hypotheses around ``center``, nearest first (ties in a fixed order), at most ``max_hypotheses``:
    translations across its optical axis, rotations about it."""
    step = max(float(config.grid_step_px) * depth_m / focal_px, 1e-6)
    radius = max(min(float(config.speed_m_s) * max(elapsed_s, 0.0), float(config.max_radius_m)), step)
    n = int(math.floor(radius / step + 1e-9))
    n_yaw = int(math.floor(float(config.yaw_range_deg) / float(config.yaw_step_deg) + 1e-9))
    offsets = []
    for k in range(-n_yaw, n_yaw + 1):
        for i in range(-n, n + 1):
            for j in range(-n, n + 1):
                if i * i + j * j <= n * n:
                    offsets.append((i * i + j * j + k * k, abs(k), k, i, j))
    offsets.sort()
    offsets = offsets[: int(config.max_hypotheses)]
    grid = np.empty((len(offsets), 4, 4))
    for m, (*_, k, i, j) in enumerate(offsets):
        T = center @ _rz(math.radians(k * float(config.yaw_step_deg)))
        T[:3, 3] = center[:3, 3] + center[:3, :3] @ np.array([i * step, j * step, 0.0])
        grid[m] = T
    return grid


class Reacquisition:
    """The search of one :class:`~evpose.tracker.tracker.Tracker` (idle until :meth:`begin`)."""

    def __init__(self, config: ReacquisitionConfig) -> None:
        self.config = config
        self.state: _State | None = None
        self.last_restart: tuple[int, np.ndarray, np.ndarray | None] | None = None
        """(time, pose, velocity) the accepted trial started from (``evpose track --smoothed`` replays from there)."""

    @property
    def active(self) -> bool:
        return self.state is not None

    def begin(self, center: np.ndarray, t_center_us: int, velocity: np.ndarray | None, reason: str) -> None:
        """Search from now on around ``center`` (the pose at ``t_center_us`` the tracker would restart from)."""
        v = None if velocity is None else np.array(velocity, dtype=np.float64)
        self.state = _State(np.array(center, dtype=np.float64), int(t_center_us), v, reason)

    def snapshot(self):
        if self.state is None:
            return None
        # Trial states are never changed in place (a trial's next state is a new snapshot): sharing them is safe.
        trials = [dataclasses.replace(t, z=list(t.z), share=list(t.share)) for t in self.state.trials]
        return dataclasses.replace(self.state, trials=trials)

    def restore(self, snap) -> None:
        self.state = snap
        self.state = self.snapshot()

    # ------------------------------------------------------------------ update
    def new_round(self, tracker: Tracker, t_us: int) -> None:
        """Start a trial per hypothesis at ``t_us`` from the tracker's state (its front end has seen the events up to
        ``t_us``)."""
        st, cfg = self.state, self.config
        st.updates, st.idle, st.trials = 0, 0, []
        base = self._detached(tracker)
        elapsed_s = (t_us - st.t_center_us) * 1e-6
        grid = hypotheses(cfg, st.center, _median_depth(tracker, st.center), float(tracker.K[0, 0]), elapsed_s)
        for h, T in enumerate(grid):
            trial = _Trial(T.copy(), None if st.velocity is None else st.velocity.copy(), centre=h == 0)
            self._attach(tracker, base)
            self._start(tracker, trial, t_us)
            trial.state = self._detached(tracker)
            st.trials.append(trial)
        self._attach(tracker, base)

    def step(self, tracker: Tracker, until: int, events: EventArray, imu: ImuSamples | None) -> StepResult:
        """One update of every trial of the round; at its end, the judgement (and a new round when none is accepted)."""
        t_total, cpu_total = time.perf_counter(), time.thread_time()
        st, cfg = self.state, self.config
        motion = tracker.components.motion
        log = None if motion is None else motion.input_log
        chance = tracker.chance_until_us
        st.updates += 1
        tracker.chance_until_us = until
        if motion is not None:
            motion.input_log = None  # the trials' reports are not the run's
        try:
            registered = False
            for trial in st.trials:
                self._attach(tracker, trial.state)
                r = tracker.track(until, events, imu)
                registered = registered or bool(r.counts.get("registered"))
                trial.result = r
                trial.state = self._detached(tracker)
            scores = [self._own_evidence(t.result.counts) for t in st.trials]
            if registered:
                # Only updates where some trial registered count: in an event-poor stretch none does, and the trials
                # (the fusion's IMU propagation of each hypothesis) simply go on.
                for trial, (z, share) in zip(st.trials, scores):
                    trial.z.append(z)
                    trial.share.append(share)
            else:
                st.updates -= 1
                st.idle += 1
        finally:
            tracker.chance_until_us = chance
            if motion is not None:
                motion.input_log = log
        ranked = sorted(st.trials, key=lambda t: (-t.evidence()[0], -t.evidence()[1]))
        counts = {"events_in": len(events), "registered": 0, "trials": len(st.trials)}
        # Any trial's state has the front end that saw these events; the best one's goes on.
        self._attach(tracker, ranked[0].state)
        if st.updates == 0 and st.idle >= int(cfg.max_idle_updates):
            # Nothing registered for long: start over around where the hypotheses' propagation has them now.
            st.rounds += 1
            self._recenter()
            result = StepResult(until, ranked[0].result.pose.copy(), TrackStatus.LOST,
                                f"{st.reason}; re-acquisition round {st.rounds}: no hypothesis registered in"
                                f" {st.idle} updates: searching again", counts=counts)
            self.new_round(tracker, until)
        elif st.updates < int(cfg.trial_updates):
            if st.updates == int(cfg.prune_after) and scores and any(z > 0 for z, _ in scores):
                kept = ranked[: max(int(cfg.keep_trials), 2)]
                # The centre's trial goes on too: it carries the centre of the next round.
                st.trials = kept + [t for t in st.trials if t.centre and all(t is not k for k in kept)]
            best = ranked[0].evidence()
            where = (f"update {st.updates} of {cfg.trial_updates} (best median z {best[0]:.1f})" if st.updates
                     else f"none registered yet ({st.idle} updates)")
            result = StepResult(until, ranked[0].result.pose.copy(), TrackStatus.LOST,
                                f"{st.reason}; re-acquisition round {st.rounds + 1}: {len(ranked)} pose hypotheses"
                                f" tracked, {where}", counts=counts)
        else:
            winner, reason = self._judge(tracker, ranked, counts)
            if winner is None:
                result = StepResult(until, ranked[0].result.pose.copy(), TrackStatus.LOST, reason, counts=counts)
                self._recenter()
                self.new_round(tracker, until)
            else:
                self._attach(tracker, winner.state)
                self.state = None
                result = dataclasses.replace(winner.result, counts={**winner.result.counts, **counts, "reacquired": 1})
        result.timings_ms = {**result.timings_ms, "reacquisition": (time.perf_counter() - t_total) * 1e3,
                             "total_cpu": (time.thread_time() - cpu_total) * 1e3}
        return result

    def _judge(self, tracker: Tracker, ranked: list, counts: dict):
        """(trial to go on from or None, reason when None) at the end of a round."""
        st, cfg = self.state, self.config
        best = ranked[0]
        z, share = best.evidence()
        end = best.result.pose
        depth = _median_depth(tracker, end)
        rival = next((t for t in ranked[1:] if self._distinct(tracker, end, t.result.pose, depth)), None)
        rival_z = rival.evidence()[0] if rival is not None else 0.0
        counts.update(search_z=round(z, 3), search_rival_z=round(rival_z, 3))
        why = []
        if z < cfg.min_z:
            why.append(f"best median z {z:.1f} < {cfg.min_z:g}")
        if share < cfg.min_inlier_share:
            why.append(f"inlier share {share:.2f} < {cfg.min_inlier_share:g}")
        if z < cfg.margin * rival_z:
            why.append(f"best z {z:.1f} not {cfg.margin:g}x the runner-up's {rival_z:.1f}")
        if why:
            st.rounds += 1
            return None, f"{st.reason}; re-acquisition round {st.rounds} found no pose ({', '.join(why)}): searching again"
        self.last_restart = (int(best.result.t_us), best.result.pose.copy(),
                             None if best.result.velocity is None else best.result.velocity.copy())
        return best, ""

    @staticmethod
    def _own_evidence(c: dict) -> tuple[float, float]:
        """(chance-level z, inlier share) of a trial's own registration (0 when it did not register)."""
        if not c.get("registered"):
            return 0.0, 0.0
        z = chance_z(c)
        return (0.0 if z is None else max(float(z), 0.0)), int(c.get("inliers", 0)) / max(int(c.get("points_in_image", 0)), 1)

    def _recenter(self) -> None:
        """The next round searches around the centre's trial: the pose the tracker would have restarted from, carried
        on by the fusion's IMU propagation with the last velocity (in ``stpe``, its motion model) and whatever its
        registrations did."""
        centre = next((t.result for t in self.state.trials if t.centre), None)
        if centre is not None and np.isfinite(centre.pose).all():
            self.state.center = centre.pose.copy()

    def _distinct(self, tracker: Tracker, a: np.ndarray, b: np.ndarray, depth: float) -> bool:
        """Whether the map's image moves ``distinct_px`` or more between the poses ``a`` and ``b``."""
        d = gtsam.Pose3(a).between(gtsam.Pose3(b))
        angle = float(np.linalg.norm(gtsam.Rot3.Logmap(d.rotation())))
        return float(tracker.K[0, 0]) * (angle + float(np.linalg.norm(d.translation())) / depth) >= float(self.config.distinct_px)

    def _detached(self, tracker: Tracker) -> dict:
        """The tracker's state without the search's own (a trial's snapshot must not hold the other trials)."""
        st, self.state = self.state, None
        try:
            return tracker.snapshot()
        finally:
            self.state = st

    def _attach(self, tracker: Tracker, state: dict) -> None:
        st = self.state
        tracker.restore(state)
        self.state = st

    @staticmethod
    def _start(tracker: Tracker, trial: _Trial, t_us: int) -> None:
        """Start the tracker at the trial's pose with its velocity (as a start from ground truth would)."""
        v = trial.velocity
        motion = tracker.components.motion
        if motion is not None:
            motion.initial_velocity_world = v
            selector = tracker.components.polarity_selector
            if selector is not None and selector.fused_pose:
                selector.hold_updates = 0 if v is not None else int(tracker.config.polarity.unknown_velocity_hold_updates)
        tracker.start(trial.start, t_us)
        if v is not None and not tracker.components.drives_pose:
            # As TrackingSession._seed_velocity: the motion model learns the velocity from a pose one update earlier.
            dt_us = max(int(round(1e6 / float(tracker.config.rate_hz))), 1)
            prev = trial.start.copy()
            prev[:3, 3] -= v * dt_us * 1e-6
            tracker.predictor.reset(t_us - dt_us, prev)
            tracker.predictor.update(t_us, trial.start)
