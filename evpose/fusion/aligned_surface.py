"""The polarity filter's output: the aligned time surface ``T_align`` registration reads (EV-Pose Alg. 1, lines 5-11).

The paper filters *events*: in the patch of each projected map point only the
time surface of the point's predicted polarity is used (both in the buffer
zone), and ``T_align`` is composed from these patches. Pixels in no patch carry
no map evidence (texture the map lacks, noise, moving objects), so they are not
shown to registration either. We compose it per pixel from the SP-TS's
last-timestamp maps:

* every pixel within ``align_patch_radius_px`` of the projection (at the
  predicted pose) of a used map point belongs to the patch of its nearest such
  point and accepts that point's predicted polarity (ON, OFF, or both for the
  buffer zone / unknown sign);
* a pixel accepting ON only reads the ON map, OFF only the OFF map, both the
  combined map;
* unmarked pixels read "never fired" (TDF 1, no gradient).

Registration then needs one field (slot 0) built from ``T_align`` instead of up
to three per-polarity fields, and its points no longer see distractor edges
between the map's contours.

"Events removed" is counted per step over the events that entered the SP-TS:
an event is removed when its pixel is in no patch or its polarity is not the one
the patch accepts; ``T_align`` never shows it to registration.

Measured on the simulated moderate landing (346x260, full mode, 4 px patches):
with the map of geometric contours alone about half the events were removed;
with the map's albedo contours added (the map then explains most edges) 15 %
(13 % outside patches, 2.5 % of the wrong polarity). Accuracy equals that of
per-point polarity fields over the whole box (21.0 vs 20.4-21.0 mm ATE); the
distance field shrinks to one slot (0.44 vs 1.4 ms), paid back by composing
(~0.8 ms CPU on a loaded machine).

The composed map is kept as a list of patch pixels and the timestamps they show
(:meth:`AlignedTimeSurface.patch_times`), not as an image: the tracker builds the
distance field from the list (:mod:`evpose.fusion.aligned_field`, bit for bit the
field of the image), and :meth:`AlignedTimeSurface.last_of` scatters the image
only when asked (viewer, tests, the coarse field).

Cost (session 8, textured landing 346x260 seed 0, ``stpe+filter``, ~900 points, ~13,000 patch pixels, ~4,100
events per update, load 0.9-2.2): ``compose`` takes 0.63-0.70 ms per update in a run (``_mark_patches`` 0.31,
``_select_times`` 0.20, ``_judge_events`` 0.10 ms wall), but 0.18-0.22 ms when called again and again on one
update's inputs, and 0.56 ms for marking and selecting after 64 MB of other memory traffic: the kernels wait on
memory, not on arithmetic. Tried on the same inputs, paired, bit for bit the same outputs, none kept: one 12-byte
record per pixel instead of the three arrays (0.98x), points sorted by image row (1.08x, slower), the disk's row extent
instead of the square (1.41x, slower), 2 MB pages for every array (0.99x), a branch-free selection (0.95x), per-
pixel slots into compact per-update arrays (marking 1.00x, selecting 0.80x: 45 us). Session 11, ``full`` seed 0,
in a run: selecting by a scan of the box's tags row by row (the maps then read in row order) 112-149 -> 173 us.
Session 12 (demo ``full``, kernels timed on captured inputs after 48 MB of other traffic, outputs compared): flat
views with one unsigned offset per pixel (no 2-D index arithmetic with negative-index wrap per access) took
``_select_times`` 294-307 -> 165-170 us, ``_mark_patches`` 439-473 -> 370-418 us (with the squared column offsets
computed once per point), ``_judge_events`` 69-84 -> 58-76 us; not kept: ``_mark_patches`` visiting only each row's
columns within the radius (a square root per row) 236-243 -> 272-280 us hot (slower), the same flat views in
:func:`~evpose.fusion.aligned_field._sparse_tdf` (82-91 -> 78-86 us: one array, written at each pixel once).
Session 14 (captured ``stpe+filter`` inputs, caches flushed before each call, alternated, outputs compared): marking
without the ``dist2`` map, the distance of a pixel's owner recomputed from its projection on each overlap (the same
float32 values), 390-401 -> 403-417 us (slower). The reopening check of ``polarity.reopen_contradicted`` now runs in
the selecting pass (:func:`_select_times_reopening`) instead of a second pass over the patch pixels with 2-D indexing,
bit for bit the same: 233 us against 172 us for selecting alone (same captured inputs, caches flushed); a second pass
that reads the other polarity only at the pixels of points still without events took 329 us.
Session 17 (captured ``stpe+filter`` inputs, 346x260, caches flushed, outputs compared; not kept): ``_mark_patches``
branch-free (every disk pixel read and written back) 255 -> 313 us; one uint64 cell per pixel (float32 bits of the
distance, owner, tag: one array, compared as integers) 315 -> 307 us. Warming the three maps first takes it 309 -> 195
us (hot 127): the cost is the ~2,000 cache lines the patches cover, whatever their layout. ``defer_events`` (the
event pass after the pose; ``stpe+filter`` only, see :meth:`MapPolaritySelector.align
<evpose.fusion.map_polarity_selector.MapPolaritySelector.align>`) moves work, it does not save any: the grid is colder
by then.
Session 21 (kept, bit for bit the same outputs): the kernels prefetch what they read next (:mod:`evpose.fusion.cache_prefetch`):
``_select_times_reopening`` the three SP-TS maps 16 patch pixels ahead, ``_judge_events`` the grid 16 events ahead,
``_mark_patches`` the patch rows of the point 4 points on (projections first, in their own pass). CPU per update in a
run, ``stpe+filter`` 346x260 seed 0, this code and the code before alternated in separate processes, three pairs:
selecting 0.121-0.164 -> 0.113-0.119 ms, judging 0.046-0.056 -> 0.035-0.038 ms, marking (prototype, three pairs)
0.240-0.257 -> 0.229-0.246 ms. What marking costs in a run is mostly not the caches: 150 consecutive steps' captured
inputs replayed in a loop (the grid stays in cache) take 180-210 us per call, one step's inputs again and again 75 us;
calling each input twice in a row, the second call takes 120 against 166 us, and flushing 8 MB between the two adds
only 12 us, so it is the data-dependent branches, which a repeated input trains. Timings of one captured input called
again and again (sessions 12-17) understate them. Not faster on the 150-step replay, not kept: branch-free marking (every
pixel of the square read and written back through selects) 220 against 204-212 us; each row's disk run found first
(branch-free) and only its pixels visited 224-234 against 181-198 us.
"""

from __future__ import annotations

import numpy as np

from evpose.frontend.noise_filter import NEVER_US
from evpose.frontend.time_surface import ideal_pixel_lut, kernel_lut
from evpose.fusion.aligned_surface_kernels import (
    _classify_owned, _judge_events, _mark_patches, _reset_touched, _scatter_times, _select_times,
    _select_times_reopening,
)

ACCEPT_ON = np.uint8(1)
ACCEPT_OFF = np.uint8(2)
ACCEPT_BOTH = np.uint8(3)
_MAX_GENERATION = (1 << 14) - 1
"""Generations fit a uint16 tag above the two polarity bits; after this many composes the tags are cleared once."""


class AlignedTimeSurface:
    """``T_align``: the SP-TS seen through the predicted polarity of each map point's patch.

    Quacks like :class:`~evpose.frontend.time_surface.SeparatedTimeSurface` for
    :meth:`TemporalDistanceField.compute <evpose.frontend.distance_field.TemporalDistanceField.compute>`
    (``config`` and ``last_of(0)``), valid inside the box of the last :meth:`compose`.
    It holds no state between steps: everything is rebuilt from the SP-TS.
    """

    def __init__(self, width: int, height: int, calibration=None):
        self.width = int(width)
        self.height = int(height)
        self._lut = kernel_lut(ideal_pixel_lut(self.width, self.height, calibration))  # empty: the identity
        # Per pixel ``generation * 4 + accepted polarity``: a pixel is in a patch of the last compose only when
        # tagged with its generation, so nothing but the composed map needs a reset between steps.
        self._tag = np.zeros((self.height, self.width), np.uint16)
        self._gen = 0
        self._dist2 = np.full((self.height, self.width), np.inf, np.float32)
        self._owner = np.full((self.height, self.width), -1, np.int32)
        self._polarity = np.zeros(0, np.int8)
        self.last_point_count = -1
        """Number of points of the last :meth:`compose` (-1 before the first)."""
        # Pixels (row, column) of the last compose's patches and the timestamp each selects: all the map holds.
        # Every array reads "no patch" everywhere else, which keeps a step's output independent of the steps before.
        self._touched = np.empty((self.height * self.width, 2), np.int32)
        self._times = np.empty(self.height * self.width, np.int64)
        self._n_touched = 0
        # The composed image, built only when :meth:`last_of` asks (the tracker's distance field reads the list):
        # ``_written`` lists the pixels it holds timestamps at, to reset them before the next build.
        self._last = np.full((self.height, self.width), NEVER_US, np.int64)
        self._written = np.empty((0, 2), np.int32)
        self._last_fresh = True
        self.field_cache: dict = {}
        """Scratch of :func:`~evpose.fusion.aligned_field.fill_distance_field` (decay table, buffer), reused between steps."""
        self.box = np.zeros(4, np.int64)
        self.point_has_events = np.zeros(0, np.bool_)
        """bool (M,) of the last :meth:`compose`: the point's patch shows a recent accepted event."""
        self.config = None
        self.last_counts: dict = {}
        self._judged = None
        """(r^2, count, first and last time, labels, points, per-point majority polarity) of the kept events of the last
        compose, for :meth:`kept_labels` / :meth:`batch_judgement`."""
        self._pending = None
        """(events, keep, r^2) of a compose whose event pass :meth:`judge` has yet to run (``defer_events``)."""

    def compose(self, surface, points_world: np.ndarray, T_world_cam: np.ndarray, K: np.ndarray, polarity: np.ndarray,
                radius_px: float, roi: tuple[int, int, int, int] | None, events=None, keep: np.ndarray | None = None,
                t_us: int | None = None, empty_after_eta: float = 3.0, classify_radius_px: float | None = None,
                reopen_contradicted: bool = False, defer_events: bool = False) -> "AlignedTimeSurface":
        """Build ``T_align`` in ``roi`` from ``surface`` for map points (M, 3) with predicted ``polarity`` (M,) at ``T_world_cam``.

        ``events`` / ``keep`` (the step's batch and the mask of those stored in
        ``surface``) are only counted: :attr:`last_counts` says how many the filter removed.
        :attr:`point_has_events` marks the points whose own patch pixels hold an
        accepted event younger than ``empty_after_eta`` time-surface constants at
        ``t_us`` (default: the newest event of the batch, or none is recent).
        With ``reopen_contradicted`` a single-polarity point whose patch holds no
        such event but one of the other polarity accepts both (see :func:`_select_times_reopening`).
        The same pass labels the kept events as :meth:`classify` would within
        ``classify_radius_px`` (default ``radius_px``), so classifying them afterwards costs nothing.
        With ``defer_events`` that pass (and the event counts of :attr:`last_counts`) waits for :meth:`judge`, or the
        first :meth:`kept_labels` / :meth:`batch_judgement`: registration needs none of it, so the tracker runs it after
        the pose is out (``keep`` is copied; ``events`` must stay unchanged until then).
        """
        if t_us is None:
            t_us = int(events.t[-1]) if events is not None and len(events) else int(NEVER_US)
        r0, r1, c0, c1 = (0, self.height, 0, self.width) if roi is None else (int(v) for v in roi)
        self.box[:] = (max(r0, 0), min(r1, self.height), max(c0, 0), min(c1, self.width))
        self.config = surface.config
        T = np.asarray(T_world_cam, np.float64)
        R_cw = np.ascontiguousarray(T[:3, :3].T)
        t_cw = -R_cw @ T[:3, 3]
        pts = np.ascontiguousarray(points_world, np.float64).reshape(-1, 3)
        pol = np.array(polarity, np.int8).reshape(pts.shape[0])  # a copy: reopened points change it
        self.last_point_count = int(pol.size)
        self._gen += 1
        if self._gen > _MAX_GENERATION:  # tags would repeat: start over from an all-empty map
            self._tag.fill(0)
            self._gen = 1
        self._n_touched = int(_mark_patches(pts, R_cw, t_cw, float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), pol,
                                            float(radius_px), self.box, np.uint16(self._gen), self._tag, self._dist2, self._owner,
                                            self._touched))
        self.point_has_events = np.zeros(pts.shape[0], np.bool_)
        recent = np.int64(t_us) - np.int64(round(float(empty_after_eta) * float(surface.config.eta_ms) * 1e3))
        reopened = 0
        if reopen_contradicted:
            reopened = int(_select_times_reopening(self._touched, self._n_touched, self._tag, self._owner, surface.last_of(1),
                                                   surface.last_of(-1), surface.last_of(0), recent, self._times, self.point_has_events,
                                                   pol, np.zeros(pts.shape[0], np.bool_)))
        else:
            _select_times(self._touched, self._n_touched, self._tag, self._owner, surface.last_of(1), surface.last_of(-1),
                          surface.last_of(0), recent, self._times, self.point_has_events)
        self._polarity = pol
        self._last_fresh = False
        counts = {"points_single_polarity": int(np.count_nonzero(pol)), "points_both": int(pol.size - np.count_nonzero(pol)),
                  "points_with_events": int(np.count_nonzero(self.point_has_events)), "points_reopened": reopened}
        self._judged = None
        self.last_counts = counts
        self._pending = None
        if events is not None and len(events):
            k = np.ones(len(events), np.bool_) if keep is None else np.array(keep, np.bool_)
            self._pending = (events, k, float(radius_px if classify_radius_px is None else classify_radius_px) ** 2)
            if not defer_events:
                self.judge()
        else:
            counts.update(events_polarity_judged=0, events_polarity_removed=0, events_outside_patches=0, events_wrong_polarity=0)
        return self

    def judge(self) -> None:
        """The event pass :meth:`compose` deferred (``defer_events``), if any: labels the kept events and adds the
        event counts to :attr:`last_counts`. Nothing else of the compose changes."""
        if self._pending is None:
            return
        events, k, r2 = self._pending
        self._pending = None
        pol = self._polarity
        n_kept = int(np.count_nonzero(k))
        label = np.empty(n_kept, np.int8)
        point = np.empty(n_kept, np.int32)
        majority = np.empty(pol.size, np.int8)
        n, outside, wrong = _judge_events(events.x, events.y, events.p, k, self.width, self._lut, np.uint16(self._gen),
                                          self._tag, self._owner, self._dist2, self.box, pol, r2, label, point, majority)
        if n_kept:  # first / last kept times by index: no copy of every kept timestamp
            first, last = int(np.argmax(k)), k.shape[0] - 1 - int(np.argmax(k[::-1]))
            self._judged = (r2, n_kept, int(events.t[first]), int(events.t[last]), label, point, majority)
        self.last_counts.update(events_polarity_judged=int(n), events_polarity_removed=int(outside + wrong),
                                events_outside_patches=int(outside), events_wrong_polarity=int(wrong))

    def classify(self, events, radius_px: float) -> tuple[np.ndarray, np.ndarray]:
        """``(label, point)`` of events against the last :meth:`compose`'s patches and polarities, as
        :func:`~evpose.fusion.polarity.classify_events` gives them (at the predicted pose), without another grid."""
        n = len(events)
        label = np.empty(n, np.int8)
        point = np.empty(n, np.int32)
        if n:
            _classify_owned(events.x, events.y, events.p, self.width, self._lut, np.uint16(self._gen), self._tag, self._owner,
                            self._dist2, self.box,
                            self._polarity, float(radius_px) ** 2, label, point)
        return label, point

    def kept_labels(self, events, radius_px: float) -> tuple[np.ndarray, np.ndarray] | None:
        """:meth:`classify` of ``events`` when they are the kept events of the last :meth:`compose` (given its
        ``keep``) and ``radius_px`` its ``classify_radius_px``: labelled in compose's pass, no second one. None when
        they are not (same count and first/last times are checked)."""
        self.judge()
        j = self._judged
        n = len(events)
        if j is None or n != j[1] or float(radius_px) ** 2 != j[0] or int(events.t[0]) != j[2] or int(events.t[-1]) != j[3]:
            return None
        return j[4].copy(), j[5].copy()

    def batch_judgement(self, events, keep: np.ndarray, radius_px: float) -> tuple[np.ndarray, np.ndarray] | None:
        """``(label, majority)`` of the kept events of the batch ``events`` / ``keep`` when they are those of the last
        :meth:`compose` (checked as in :meth:`kept_labels`): the labels of :meth:`kept_labels` and each point's majority
        polarity (:func:`~evpose.fusion.event_labels.observed_point_polarity` of its events), without copying the kept
        events. Views, valid until the next compose. None when they are not."""
        self.judge()
        j = self._judged
        k = np.ascontiguousarray(keep, np.bool_)
        if j is None or float(radius_px) ** 2 != j[0] or k.shape[0] != len(events):
            return None
        n = int(np.count_nonzero(k))
        if n != j[1] or not n:
            return None
        first, last = int(np.argmax(k)), k.shape[0] - 1 - int(np.argmax(k[::-1]))
        if int(events.t[first]) != j[2] or int(events.t[last]) != j[3]:
            return None
        return j[4], j[6]

    @property
    def accept(self) -> np.ndarray:
        """uint8 (H, W): polarity each pixel's patch accepts in the last :meth:`compose` (1 ON, 2 OFF, 3 both, 0 in
        no patch); a new array (for reports, the viewer and tests)."""
        current = (self._tag >> 2) == self._gen
        return np.where(current & (self._gen > 0), self._tag & 3, 0).astype(np.uint8)

    def last_of(self, polarity: int) -> np.ndarray:
        """int64 (H, W) composed last-timestamp map (``T_align`` has one polarity slot: 0)."""
        if int(polarity) != 0:
            raise ValueError("the aligned time surface has only the combined slot (0)")
        if not self._last_fresh:
            _reset_touched(self._written, self._written.shape[0], self._last)
            _scatter_times(self._touched, self._n_touched, self._times, self._last)
            self._written = self._touched[:self._n_touched].copy()
            self._last_fresh = True
        return self._last

    def patch_times(self) -> tuple[np.ndarray, np.ndarray]:
        """(pixels int32 (n, 2) as (row, column), timestamps int64 (n,)): the patch pixels of the last :meth:`compose`
        and what ``T_align`` shows there (views, valid until the next compose); every other pixel reads NEVER."""
        n = self._n_touched
        return self._touched[:n], self._times[:n]
