"""Engine snapshots in the disk cache: a seek past what is computed resumes from the farthest one on disk, and what it
shows equals a headless run bit for bit; a damaged snapshot file falls back to an earlier one, never a failure."""

import numpy as np
import pytest
from app_scenes import old_and_recent_entries

from app.disk_cache import DiskCache, DiskCacheConfig, cache_key
from app.disk_snapshots import live_smoothers
from app.frame_cache import FrameCacheConfig
from app.tracker_engine import TrackerEngine
from evpose.tracker.session import TrackingSession

CHUNK = 20


@pytest.fixture(scope="module")
def headless(squares_scene):
    rec, cmap = squares_scene
    s = TrackingSession(rec, cmap)
    return [s.step() for _ in range(s.total_steps)]


def _engine(scene, tmp_path, files):
    conf = DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=CHUNK)
    return TrackerEngine(*scene, cache=FrameCacheConfig(every_ms=25.0),
                         disk=lambda config, every: DiskCache(conf, *cache_key(*files, config, every, sources="test")))


def _prepare_part(scene, tmp_path, files, steps):
    """An opening whose run-ahead stopped after ``steps`` steps (a warm-up cut short, a recording watched half-way)."""
    eng = _engine(scene, tmp_path, files)
    eng.step()
    while eng.frontier < steps:
        eng.prefetch(1)
    eng.flush_disk_snapshots()  # those taken on the way, encoded on their own thread
    return eng


def _assert_history_equals(eng, ref, upto):
    hist = eng._summaries[: upto + 1]
    assert [s.index for s in hist] == list(range(upto + 1))
    for s, r in zip(hist, ref):
        assert np.array_equal(s.pose, r.pose) and s.status == r.status.value and s.t_us == r.t_us


def test_the_scene_tracks_with_the_fusion_smoother_that_cannot_be_pickled(squares_scene):
    assert list(live_smoothers(TrackingSession(*squares_scene).tracker)) == ["predictor"]


def test_a_far_seek_restores_the_farthest_disk_snapshot_and_equals_the_headless_run(squares_scene, tmp_path, pair_files,
                                                                                   headless):
    first = _prepare_part(squares_scene, tmp_path, pair_files, 50)
    assert sorted(first.disk.snapshots_written) == [0, 1]  # steps 20 and 40; chunk 2 ends at 60
    assert all(not sm.journal or len(sm.journal) < 200 for sm in live_smoothers(first._ahead.tracker).values())
    second = _engine(squares_scene, tmp_path, pair_files)
    assert second.disk_steps == 40 and second.frontier == 0
    second.seek(second.t_start_us)
    k = 85
    t = headless[k].t_us
    assert second.catch_up_steps(t, exact=True) == k - 40  # from the disk snapshot at step 40, not from step 0
    # The player slices by cost, which counts the restore (the fusion journal of the 40 steps before it) too.
    assert second.catch_up_cost_steps(t, exact=True) > k - 40
    # The restore is sliced too (a command waits at most one file's journal replay): snapshot 1 needs file 0's first.
    assert second.catch_up(t, 10, exact=True) is False and second.frontier == 0 and second._disk_job is not None
    while not second.catch_up(t, 10, exact=True):
        pass
    f = second.seek(t)
    assert f.index == k and np.array_equal(f.pose, headless[k].pose) and f.status == headless[k].status.value
    assert np.array_equal(f.residuals, headless[k].debug.residuals) if headless[k].debug is not None else True
    _assert_history_equals(second, headless, k)
    # The run-ahead jumped to step 40 and queued the later snapshots (a seek does not wait for their writing); idle
    # time writes them, and their replay equals the headless run too.
    assert sorted(second.disk.snapshots_written) == [0, 1] and [q[0] for q in second._disk_queue] == [2, 3]
    for _, _, encoding in second._disk_queue:
        encoding.result(60)  # encoded on the encoder thread meanwhile
    second.prefetch(1)
    second.prefetch(1)
    assert sorted(second.disk.snapshots_written) == [0, 1, 2, 3]
    third = _engine(squares_scene, tmp_path, pair_files)
    third.seek(third.t_start_us)
    g = third.seek_step(90)  # exact, off the grid: restores the disk snapshot at step 80 and steps 11 times
    assert g.index == 90 and np.array_equal(g.pose, headless[90].pose)
    assert third.session.step_count == 91


def test_a_truncated_snapshot_is_ignored_with_a_warning_and_an_earlier_one_used(squares_scene, tmp_path, pair_files,
                                                                               headless):
    first = _prepare_part(squares_scene, tmp_path, pair_files, 62)
    assert sorted(first.disk.snapshots_written) == [0, 1, 2]
    last = first.disk._snapshot_path(2)
    last.write_bytes(last.read_bytes()[: last.stat().st_size // 2])
    second = _engine(squares_scene, tmp_path, pair_files)
    second.seek(second.t_start_us)
    with pytest.warns(RuntimeWarning, match="ignored"):
        g = second.seek_step(70)
    assert np.array_equal(g.pose, headless[70].pose)
    assert not last.exists() and sorted(second.disk.snapshots_written) == [0, 1]
    # A damaged first file: every snapshot goes, the seek computes from step 0, still exact.
    first.disk._snapshot_path(0).write_bytes(b"not a pickle")
    third = _engine(squares_scene, tmp_path, pair_files)
    third.seek(third.t_start_us)
    with pytest.warns(RuntimeWarning, match="ignored"):
        h = third.seek_step(52)  # off the kept-frame grid: computed
    assert np.array_equal(h.pose, headless[52].pose) and third.disk.snapshot_chunks() == []


def test_snapshot_files_count_in_the_entry_size_the_trimming_goes_by(squares_scene, tmp_path, pair_files):
    eng = _prepare_part(squares_scene, tmp_path, pair_files, 45)
    files = {p.name: p.stat().st_size for p in eng.disk.dir.iterdir()}
    assert {"snap_00000.pkl", "snap_00001.pkl"} <= set(files)
    from app.warm_up import cache_bytes

    assert cache_bytes(eng.disk.config.folder()) == sum(files.values())


def test_writing_a_snapshot_trims_older_entries_to_the_budget_counting_every_file(tmp_path):
    conf = DiskCacheConfig(directory=tmp_path / "cache", budget_mb=1.0)
    old_and_recent_entries(conf.folder(), "snap_00000.pkl", 400_000)  # snapshot files count as much as chunks
    disk = DiskCache(conf, "current", {})
    disk.dir.mkdir(parents=True)
    (disk.dir / "meta.json").write_text("{}")
    disk.write_snapshot(0, b"header", b"y" * 300_000)
    assert sorted(p.name for p in conf.folder().iterdir()) == ["current", "recent"]
    assert disk.snapshots_written == {0} and disk.snapshot_chunks() == [0]


def test_with_snapshots_off_nothing_is_stored_and_a_far_seek_computes_from_step_0(squares_scene, tmp_path, pair_files,
                                                                                  headless):
    _prepare_part(squares_scene, tmp_path, pair_files, 50)
    conf = DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=CHUNK, snapshots=False)
    eng = TrackerEngine(*squares_scene, cache=FrameCacheConfig(every_ms=25.0),
                        disk=lambda config, every: DiskCache(conf, *cache_key(*pair_files, config, every, sources="test")))
    eng.seek(eng.t_start_us)
    assert eng.disk.snapshot_chunks() == [] and eng.catch_up_steps(headless[70].t_us, exact=True) == 70
    off = _engine(squares_scene, tmp_path / "off", pair_files)
    off.disk.config.snapshots = False
    off.step()
    while off.frontier < 45:
        off.prefetch(1)
    assert not list(off.disk.dir.glob("snap_*.pkl")) and all(
        sm.journal is None for sm in live_smoothers(off._ahead.tracker).values())


@pytest.mark.parametrize("rebase_every", [10, 0])
def test_a_restore_replays_only_the_journal_since_the_smoothers_last_re_base_at_any_depth(
        squares_scene, tmp_path, pair_files, monkeypatch, rebase_every):
    from evpose.fusion.factor_graph import FactorGraphFusion

    monkeypatch.setattr(FactorGraphFusion, "rebase_every_states", rebase_every)  # 0: never (the old restore)
    s = TrackingSession(*squares_scene)
    ref = [s.step() for _ in range(s.total_steps)]
    first = _prepare_part(squares_scene, tmp_path, pair_files, 85)
    assert sorted(first.disk.snapshots_written) == [0, 1, 2, 3]
    replayed = []
    for n in range(4):
        eng = _engine(squares_scene, tmp_path, pair_files)
        eng.seek(eng.t_start_us)
        k = (n + 1) * CHUNK + 7  # off the kept-frame grid: the disk snapshot before it restored, 7 steps computed
        g = eng.seek_step(k)
        assert g.index == k and np.array_equal(g.pose, ref[k].pose)
        replayed.append(eng.disk.replayed_entries)
    if rebase_every:  # the same few entries (those of the updates since the last re-base) at every depth
        assert len(set(replayed)) == 1 and 0 < replayed[0] < 30
    else:  # every entry since step 0: at least a chunk's updates more for each snapshot further in (not exactly a
        # chunk's worth: a large velocity correction adds a relinearising update, FusionConfig.relinearize_correction_velocity)
        assert replayed[0] > 30 and all(b - a >= CHUNK for a, b in zip(replayed, replayed[1:]))


def test_disk_snapshots_are_encoded_off_the_players_thread_and_written_in_order(squares_scene, tmp_path, pair_files,
                                                                                monkeypatch):
    import threading

    import app.disk_snapshots as ds

    threads, written = [], []
    encode = ds.encode
    monkeypatch.setattr(ds, "encode", lambda *a: threads.append(threading.get_ident()) or encode(*a))
    write = DiskCache.write_snapshot
    monkeypatch.setattr(DiskCache, "write_snapshot", lambda self, n, h, b: written.append(n) or write(self, n, h, b))
    eng = _prepare_part(squares_scene, tmp_path, pair_files, 85)
    assert written == [0, 1, 2, 3] and sorted(eng.disk.snapshots_written) == [0, 1, 2, 3]
    assert len(threads) == 4 and threading.get_ident() not in threads
    assert eng.disk_snapshot_cpu_s > 0 and not eng._disk_queue


def test_snapshots_a_catch_up_queued_are_still_written_when_the_engine_is_let_go(squares_scene, tmp_path, pair_files,
                                                                                headless):
    from app.disk_snapshots import encoder

    eng = _engine(squares_scene, tmp_path, pair_files)
    eng.seek(eng.t_start_us)
    t = headless[85].t_us
    while not eng.catch_up(t, 10, exact=True):
        pass
    queued = [q[0] for q in eng._disk_queue]
    assert queued == [0, 1, 2, 3] and not eng.disk.snapshots_written  # a seek does not wait for their writing
    eng.release()  # another recording opened: the encoder thread writes them
    encoder().submit(lambda: None).result(60)
    assert sorted(eng.disk.snapshots_written) == queued
    again = _engine(squares_scene, tmp_path, pair_files)
    assert again.disk.snapshot_chunks() == queued
