"""Engine snapshots on disk: a seek past what the run-ahead has computed restores the farthest one instead of step 0.

A tracker snapshot (``Tracker.snapshot`` plus the session's event cursor) is
numpy arrays and plain values except the fusion's fixed-lag smoother, whose
gtsam ``ISAM2`` cannot be pickled. For it the run-ahead keeps a *journal* of
its calls (:attr:`evpose.fusion.fixed_lag.CopyableFixedLagSmoother.journal`):
each disk snapshot file holds the journal segment since the previous one
(graphs and values in gtsam's own serialisation) and the state without the
smoother. The smoother re-bases itself every
``FactorGraphFusion.rebase_every_states`` updates (headless too: it is part of
the algorithm), rebuilding iSAM2 from its factors and linearisation point, and
its journal then restarts with that content (``("rebase", graph, values,
stamps)``). Restoring the snapshot after chunk ``n`` makes the same rebuild from
the last re-base's content and replays the journal since: the same smoother bit
for bit (``tests/app/test_disk_snapshots.py``), at a cost that does not grow with
the step (~0.6 ms per replayed update, at most ``rebase_every_states`` of
them: on the 10 s landing the restore at 9 s took 13 ms with 8 journal entries
to replay, 41-56 ms with 287 entries when the last re-base was 51 updates
before, against 1.2 s replaying all 1800 steps before the re-bases). Before a smoother's first re-base the restore
copies the smoother of step 0 (a fresh session's, deterministic) and replays
segments ``0..n`` on it.

File ``snap_<n>.pkl`` (written atomically once the run-ahead has passed step
``(n + 1) * chunk_steps``): two pickles, the header ``{"version", "step",
"journal": zlib bytes, "rebased": keys of the smoothers whose segment starts
with a re-base}`` and then the zlib-compressed state, so the segments of
earlier files are read without their states.
"""

from __future__ import annotations

import pickle
import zlib

import numpy as np

VERSION = 2
"""Layout of a snapshot file; a file of another version is ignored."""
LEVEL = 1
"""zlib level: 1 packs a snapshot of the 10 s landing 3.7 -> 1.0 MB in 40 ms (level 6 saves ~20 % more, 4x slower)."""
MAX_QUEUED = 8
"""Disk snapshots waiting to be written beyond which the oldest is written at once, waiting for its encoding if need be
(~4.6 MB each in memory until encoded, ~1 MB after, on the 10 s landing: a long catch-up must not hold them all)."""
_ENCODER = None
"""The one thread that encodes disk snapshots for every engine of this process (:func:`encoder`)."""
_GRAPHS = ("update", "rebase")
"""Journal entries ``(name, graph, values, timestamps)`` whose graph and values are stored in gtsam's serialisation."""
_SMOOTHER = "__smoother_from_journal__"
"""Stands in the stored state where the smoother was."""


def live_smoothers(tracker) -> dict[str, object]:
    """The tracker's fixed-lag smoothers by the snapshot key of their owner ("predictor", "motion"): the fusion of
    the predictor and of a side motion model, when they are factor graphs."""
    from evpose.fusion.fixed_lag import CopyableFixedLagSmoother

    owners = {"predictor": tracker.predictor, "motion": tracker._side_motion()}
    out = {}
    for key, owner in owners.items():
        sm = getattr(getattr(owner, "fusion", None), "smoother", None)
        if isinstance(sm, CopyableFixedLagSmoother):
            out[key] = sm
    return out


def start_journals(tracker) -> None:
    """Journal the tracker's smoothers from now on (empty journals)."""
    for sm in live_smoothers(tracker).values():
        sm.journal = []


def take_segments(tracker) -> dict[str, list]:
    """The journal entries since the last call (or :func:`start_journals`), by owner; the journals restart empty."""
    out = {}
    for key, sm in live_smoothers(tracker).items():
        if sm.journal is not None:
            out[key], sm.journal = sm.journal, []
    return out


def _encode_segments(segments: dict[str, list]) -> bytes:
    ser = {key: [(e[0], None if e[1] is None else e[1].serialize(), None if e[2] is None else e[2].serialize(), *e[3:])
                 if e[0] in _GRAPHS else e for e in entries] for key, entries in segments.items()}
    return zlib.compress(pickle.dumps(ser, protocol=pickle.HIGHEST_PROTOCOL), LEVEL)


def _decode_segments(blob: bytes) -> dict[str, list]:
    import gtsam

    def load(cls, text):
        if text is None:
            return None
        obj = cls()
        obj.deserialize(text)
        return obj

    ser = pickle.loads(zlib.decompress(blob))
    return {key: [(e[0], load(gtsam.NonlinearFactorGraph, e[1]), load(gtsam.Values, e[2]), *e[3:]) if e[0] in _GRAPHS else e
                  for e in entries] for key, entries in ser.items()}


def encode(step: int, snapshot, segments: dict[str, list]) -> tuple[bytes, bytes]:
    """(header, state) bytes of a session snapshot ``(tracker state, cursor)`` at ``step`` and the journal
    segments that led to it from the previous disk snapshot."""
    state, cursor = snapshot
    stored = dict(state)
    for key in segments:
        owner = dict(stored[key])
        owner["fusion"] = {**owner["fusion"], "smoother": _SMOOTHER}
        stored[key] = owner
    body = zlib.compress(pickle.dumps((stored, cursor), protocol=pickle.HIGHEST_PROTOCOL), LEVEL)
    rebased = sorted(key for key, entries in segments.items() if entries and entries[0][0] == "rebase")
    header = pickle.dumps({"version": VERSION, "step": int(step), "journal": _encode_segments(segments),
                           "rebased": rebased}, protocol=pickle.HIGHEST_PROTOCOL)
    return header, body


def encoder():
    """The encoding thread: the player's thread only takes a snapshot and, later, writes the encoded bytes.

    Encoding is 80-85 % zlib, which releases the GIL, so it runs on the machine's other core beside the tracker's
    steps. Measured on the first opening's far seek of the 10 s landing (catch-up of 1893 steps, disk cache on,
    4 alternated pairs in separate processes, load 10-14, /tmp/s12/viewer/split_catchup.py): the player thread's CPU
    outside the tracker's steps and in-memory snapshots went 0.49-0.54 s -> 0.14-0.15 s (of 6.7-9.3 s; the tracker's
    own steps are the rest), poses bit-identical; the process's other threads spent 0.64-0.70 s meanwhile (encoding
    0.32-0.37 s of it)."""
    global _ENCODER
    if _ENCODER is None:
        from concurrent.futures import ThreadPoolExecutor

        _ENCODER = ThreadPoolExecutor(max_workers=1, thread_name_prefix="evpose-snapshot-encoder")
    return _ENCODER


def encode_timed(step: int, snapshot, segments: dict[str, list]) -> tuple[bytes, bytes, float]:
    """:func:`encode` and the CPU seconds it took on its thread."""
    import time

    c0 = time.thread_time()
    header, body = encode(step, snapshot, segments)
    return header, body, time.thread_time() - c0


def read_header(path) -> dict:
    """The header of a snapshot file (raises on a truncated, foreign or other-version file)."""
    with open(path, "rb") as f:
        header = pickle.load(f)
    if not isinstance(header, dict) or header.get("version") != VERSION:
        raise ValueError("not a snapshot file of this version")
    return header


def read_state(path):
    """The stored ``(state, cursor)`` of a snapshot file (its smoothers still to be rebuilt)."""
    with open(path, "rb") as f:
        header = pickle.load(f)
        if header.get("version") != VERSION:
            raise ValueError("not a snapshot file of this version")
        return pickle.loads(zlib.decompress(f.read()))


def _smoother_keys(state: dict) -> list[str]:
    return [k for k, v in state.items() if isinstance(v, dict) and isinstance(v.get("fusion"), dict)
            and isinstance(v["fusion"].get("smoother"), str) and v["fusion"]["smoother"] == _SMOOTHER]


def start_rebuild(stored, step0_snapshot) -> dict:
    """Copies of step 0's smoothers (``step0_snapshot``: a session's own) for each one the stored state left out."""
    base = step0_snapshot[0]
    return {key: base[key]["fusion"]["smoother"].copy() for key in _smoother_keys(stored[0])}


def replay_start(headers) -> dict[str, int]:
    """For each smoother key, the index into ``headers`` (the files up to the one restored, oldest first) of the
    last file whose segment starts with a re-base of that smoother: its replay starts there (0 if none did)."""
    start: dict[str, int] = {}
    for m in range(len(headers) - 1, -1, -1):
        for key in headers[m].get("rebased", ()):
            start.setdefault(key, m)
    return start


def replay_header(smoothers: dict, header: dict) -> int:
    """Replay one file's journal segments on the smoothers being rebuilt (files in order from the first, or from
    the one whose segment starts with each smoother's last re-base); the number of entries replayed."""
    segments = _decode_segments(header["journal"])
    n = 0
    for key, sm in smoothers.items():
        entries = segments.get(key, [])
        sm.replay(entries)
        n += len(entries)
    return n


def finish_rebuild(stored, smoothers: dict):
    """The session snapshot ``(state, cursor)``: the stored state with its rebuilt smoothers put back."""
    state, cursor = stored
    state = dict(state)
    for key, sm in smoothers.items():
        owner = dict(state[key])
        owner["fusion"] = {**owner["fusion"], "smoother": sm}
        state[key] = owner
    return state, cursor


def array_nbytes(obj) -> int:
    """Bytes of the numpy arrays in a nested snapshot (dicts, lists, tuples); other objects count as nothing."""
    if isinstance(obj, np.ndarray):
        return obj.nbytes
    if isinstance(obj, dict):
        return sum(array_nbytes(v) for v in obj.values())
    if isinstance(obj, (list, tuple)):
        return sum(array_nbytes(v) for v in obj)
    return 0


def share_snapshot(src, dst, step: int) -> None:
    """Give session ``dst`` the snapshot ``src`` keeps at ``step`` (same recording and configuration).

    ``Tracker.restore`` copies every array and the fusion smoother out of a
    snapshot, so both sessions can restore the same one.
    """
    dst.adopt_snapshot(step, src.snapshot_at(step))


class DiskSnapshotsMixin:
    """The :class:`~app.tracker_engine.TrackerEngine`'s side: write a disk snapshot at each chunk end the run-ahead
    passes, and find / adopt the farthest one for a seek (``self.disk``, ``self._summaries``, ``self._ahead``)."""

    _disk_restore_s = 0.0
    """Running estimate of one disk restore (read, unpickle, journal replay since the last re-base), seconds."""
    _disk_queue: list
    """Disk snapshots taken but not written yet: (n, step, future of their encoding)."""
    _disk_adopted: dict
    """id(session) -> step of the last disk snapshot it was given."""
    _disk_job = None
    """A disk restore under way in slices (a catch-up's): [session, step, loader generator, seconds so far]."""
    disk_snapshot_cpu_s = 0.0
    """CPU spent encoding the disk snapshots written so far, seconds (on the :func:`encoder` thread)."""
    disk_snapshot_write_cpu_s = 0.0
    """The player thread's CPU spent writing them, seconds (what they still cost the run-ahead)."""

    def _disk_base(self, k: int) -> int:
        """Step count of the farthest disk snapshot at or before step ``k`` whose steps before it all have their
        summaries (so a session restored there appends the next ones); -1 if none."""
        d = self.disk
        best, n = -1, 0
        while d is not None and n in d.snapshots_written:
            step = d.snapshot_step(n)
            if step > k or step > len(self._summaries):
                break
            best, n = step, n + 1
        return best

    def _disk_restore_cost_s(self) -> float:
        """Seconds a disk restore costs: the running estimate, or before any was measured, a chunk's journal
        replayed (~0.2 of a plain step each: an upper bound, as the smoother re-bases at least that often)."""
        return self._disk_restore_s or 0.2 * (self._step_s["plain"] or 0.01) * self.disk.chunk_steps

    def catch_up_cost_steps(self, t_us: int, exact: bool = False) -> int:
        """The engine's :meth:`catch_up_steps` plus a disk snapshot's restore, in steps of CPU time."""
        k = self._target(t_us, exact)
        steps = self.catch_up_steps(t_us, exact)
        s, start = self._start_for(k)
        in_memory = start in s.snapshot_steps or (self._ahead is not None and start in self._ahead.snapshot_steps)
        if steps and start > s.step_count and not in_memory and start == self._disk_base(k):
            # The restore replays the fusion journal since the smoother's last re-base before the disk snapshot.
            steps += int(self._disk_restore_cost_s() / (self._step_s["plain"] or 0.01))
        return steps

    def _disk_jump(self, k: int, start: int) -> int:
        """The disk snapshot step the run-ahead (at ``start``) should restore on its way to step ``k``, or -1: only
        when restoring it (which replays the fusion journal since the smoother's last re-base, at most
        ``FactorGraphFusion.rebase_every_states`` updates at ~0.6 ms each on the 10 s landing, whatever the step)
        costs less than stepping there from ``start`` (~4 ms per step)."""
        d = self._disk_base(k)
        if d <= start + self._snapshot_spacing:
            return -1
        plain = self._step_s["plain"] or 0.01
        return d if self._disk_restore_cost_s() < (d - start) * plain else -1

    def _adopt_disk(self, s, step: int) -> bool:
        """Give session ``s`` the disk snapshot at ``step`` at once; False if a file it needs was unreadable."""
        while (done := self._disk_restore_slice(s, step)) is False:
            pass
        return bool(done)

    def _disk_restore_slice(self, s, step: int):
        """One slice of giving session ``s`` the disk snapshot at ``step`` (a file's journal segment replayed):
        True once it has it, False while replaying, None if a file it needs was unreadable (dropped)."""
        import time

        job = self._disk_job
        if job is None or job[0] is not s or job[1] != step:
            loader = self.disk.snapshot_loader(step // self.disk.chunk_steps - 1, s.snapshot_at(0))
            job = self._disk_job = [s, step, loader, 0.0]
        t0 = time.perf_counter()
        try:
            next(job[2])
            job[3] += time.perf_counter() - t0
            return False
        except StopIteration as stop:
            snap = stop.value
        self._disk_job = None
        if snap is None:
            return None
        last = self._disk_adopted.get(id(s))
        if last is not None and last != step and s is not self._ahead:
            s.drop_snapshot(last)  # the shown session keeps one snapshot read from disk (~3.7 MB each), the latest
        self._disk_adopted[id(s)] = step
        s.adopt_snapshot(step, snap)
        took = job[3] + time.perf_counter() - t0
        old = self._disk_restore_s
        self._disk_restore_s = took if not old else 0.7 * old + 0.3 * took
        return True

    def _write_disk_snapshot(self, s, defer: bool = False) -> None:
        """After a run-ahead step: at a chunk end, take the fusion journal segment and, if the disk wants the snapshot
        there (every earlier one present or queued, not past the last step), hand it to the :func:`encoder` thread;
        then write the queued ones already encoded, in order. ``defer`` (a catch-up): write none now (idle time does,
        :meth:`_flush_disk_snapshot`), unless more than ``MAX_QUEUED`` wait."""
        c = self.disk.chunk_steps
        k = s.step_count
        if k % c or not self.disk.config.snapshots:
            return
        n = k // c - 1
        segments = take_segments(s.tracker)
        if set(segments) != set(live_smoothers(s.tracker)):
            return  # a smoother without its journal (cannot happen on the run-ahead; never store a wrong state)
        d = self.disk
        queued = {p[0] for p in self._disk_queue}
        if k >= self.n_steps or not d.want_snapshot(n) or n in queued or any(
                m not in d.snapshots_written and m not in queued for m in range(n)):
            return
        if k not in s.snapshot_steps:
            s.take_snapshot()
        # Snapshots are never changed once taken and the segments were taken out of the journals: the thread only reads.
        self._disk_queue.append((n, k, encoder().submit(encode_timed, k, s.snapshot_at(k), segments)))
        while len(self._disk_queue) > MAX_QUEUED:
            self._flush_disk_snapshot()
        while not defer and self._disk_queue and self._disk_queue[0][2].done():
            self._flush_disk_snapshot()

    def _flush_disk_snapshot(self, block: bool = True) -> bool:
        """Write the oldest queued disk snapshot, waiting for its encoding (``block``) or only if it is encoded;
        False if none was written."""
        if not self._disk_queue or not (block or self._disk_queue[0][2].done()):
            return False
        import time

        n, k, job = self._disk_queue.pop(0)
        d = self.disk
        try:
            header, body, cpu_s = job.result()
        except Exception as exc:  # a configuration whose state cannot be pickled: no disk snapshots, no failure
            d.snapshots_written.update(range(n, self.n_steps // d.chunk_steps + 1))
            self._disk_queue.clear()
            import warnings

            warnings.warn(f"engine snapshots are not stored on disk: {exc!r}", RuntimeWarning, stacklevel=2)
            return True
        c0 = time.thread_time()
        d.write_snapshot(n, header, body)
        self.disk_snapshot_cpu_s += cpu_s
        self.disk_snapshot_write_cpu_s += time.thread_time() - c0
        return True

    def flush_disk_snapshots(self) -> None:
        """Write every queued disk snapshot now, waiting for their encoding."""
        while self._flush_disk_snapshot():
            pass

    def release(self) -> None:
        """The engine is let go (another recording or configuration): its queued disk snapshots are written by the
        encoder thread once encoded, in order, without holding up the player (nothing else uses this disk entry)."""
        queue, self._disk_queue = self._disk_queue, []
        if queue and self.disk is not None:
            d = self.disk

            def write_all():
                for n, _, job in queue:
                    try:
                        header, body, _ = job.result()
                    except Exception:  # not picklable: no disk snapshots (as _flush_disk_snapshot)
                        return
                    d.write_snapshot(n, header, body)

            encoder().submit(write_all)  # one worker: runs after their encodings
