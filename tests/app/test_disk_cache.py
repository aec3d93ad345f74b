"""Disk cache of the run-ahead: a second opening reads back exactly what a headless run computes, and any change of
recording, map, configuration or code gives another entry."""

import dataclasses
import os

import numpy as np
import pytest
from app_scenes import old_and_recent_entries

from app.app_config import AppConfig, cache_inside_data
from app.disk_cache import DiskCache, DiskCacheConfig, cache_key
from app.frame_cache import FrameCacheConfig, quantize
from app.tracker_engine import TrackerEngine, frame_from_result
from evpose.tracker.config import TrackerConfig
from evpose.tracker.session import TrackingSession


def _maker(conf, files, made=None):
    def entry(config, every):
        disk = DiskCache(conf, *cache_key(*files, config, every, sources="test sources"))
        if made is not None:
            made.append(disk)
        return disk
    return entry


def _run_ahead(eng):
    eng.step()
    while eng.prefetch(50):
        pass


def test_a_second_opening_reads_summaries_and_frames_back_without_tracking(squares_scene, tmp_path, pair_files):
    rec, cmap = squares_scene
    conf = DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=20)
    first = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0), disk=_maker(conf, pair_files))
    _run_ahead(first)
    n = first.n_steps
    assert sorted(first.disk.written) == list(range((n + 19) // 20))
    second = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0), disk=_maker(conf, pair_files))
    assert second.ready_steps == n and second.frontier == 0 and sorted(second.cache._frames) == sorted(first.cache._frames)
    headless = TrackingSession(rec, cmap)
    k = 45
    ref = [headless.step(debug=i == k) for i in range(n)]
    f = second.seek_near(ref[47].t_us)  # a kept frame: no tracker work at all
    assert f.index == k and second.frontier == 0 and second.session.step_count == 0
    want = frame_from_result(ref[k], k)
    assert np.array_equal(f.pose, want.pose) and np.array_equal(f.residuals, want.residuals)
    assert np.array_equal(f.tdf, quantize(want.tdf)) and np.array_equal(f.events_kept.t, want.events_kept.t)
    assert [s.index for s in second.history] == list(range(k + 1))
    assert all(np.array_equal(s.pose, r.pose) and s.status == r.status.value for s, r in zip(second.history, ref))
    # Off the grid it still tracks, exactly; the run-ahead's recomputation of known steps adds no frames twice.
    g = second.seek_step(k + 2)
    assert g.index == k + 2 and np.array_equal(g.pose, ref[k + 2].pose)


def test_any_change_of_configuration_recording_or_code_is_another_entry(pair_files, tmp_path):
    cfg = TrackerConfig()
    key, _ = cache_key(*pair_files, cfg, 4, sources="a")
    assert cache_key(*pair_files, TrackerConfig(), 4, sources="a")[0] == key
    changed = dataclasses.replace(cfg, time_surface=dataclasses.replace(cfg.time_surface, eta_ms=cfg.time_surface.eta_ms + 0.5))
    assert cache_key(*pair_files, changed, 4, sources="a")[0] != key
    assert cache_key(*pair_files, cfg, 5, sources="a")[0] != key
    assert cache_key(*pair_files, cfg, 4, sources="b")[0] != key
    rec, cmap = pair_files
    rec.write_bytes(b"recording bytes, edited")
    os.utime(rec, ns=(1, 1))  # also a new modification time, as an editor would leave
    assert cache_key(rec, cmap, cfg, 4, sources="a")[0] != key
    moved = tmp_path / "elsewhere.ply"
    moved.write_bytes(cmap.read_bytes())
    rec.write_bytes(b"recording bytes")
    assert cache_key(rec, moved, cfg, 4, sources="a")[0] == key  # contents, not paths


def test_a_changed_configuration_recomputes_instead_of_reading_the_old_entry(squares_scene, tmp_path, pair_files):
    rec, cmap = squares_scene
    conf = DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=20)
    _run_ahead(TrackerEngine(rec, cmap, disk=_maker(conf, pair_files)))
    other = dataclasses.replace(TrackerConfig(), warmup_ms=TrackerConfig().warmup_ms + 5.0)
    eng = TrackerEngine(rec, cmap, other, disk=_maker(conf, pair_files))
    assert eng.ready_steps == 0 and len(eng.cache) == 0
    assert len([d for d in (tmp_path / "cache").iterdir() if d.is_dir()]) == 1  # nothing written yet for it


def test_an_unreadable_chunk_is_dropped_and_only_the_steps_before_it_are_used(squares_scene, tmp_path, pair_files):
    rec, cmap = squares_scene
    conf = DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=20)
    made = []
    _run_ahead(TrackerEngine(rec, cmap, disk=_maker(conf, pair_files, made)))
    bad = made[0].dir / "chunk_00001.pkl"
    bad.write_bytes(b"not a pickle")
    eng = TrackerEngine(rec, cmap, disk=_maker(conf, pair_files))
    assert eng.ready_steps == 20 and not bad.exists()
    _run_ahead(eng)  # the run-ahead writes it again
    assert bad.exists() and TrackerEngine(rec, cmap, disk=_maker(conf, pair_files)).ready_steps == eng.n_steps


def test_the_budget_drops_the_least_recently_used_entries(tmp_path):
    conf = DiskCacheConfig(directory=tmp_path / "cache", budget_mb=1.0)
    old_and_recent_entries(conf.folder(), "chunk_00000.pkl", 600_000)
    disk = DiskCache(conf, "current", {})
    disk.write_chunk(0, [], {})
    assert sorted(p.name for p in conf.folder().iterdir()) == ["current", "recent"]


def test_a_failing_write_turns_the_disk_cache_off_without_an_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder would be")
    disk = DiskCache(DiskCacheConfig(directory=blocker), "k", {})
    disk.write_chunk(0, [], {})
    assert disk.error and not disk.want(1)


def test_a_cache_folder_inside_a_data_folder_is_not_used(tmp_path):
    cfg = AppConfig(data=[tmp_path], disk_cache=DiskCacheConfig(directory=tmp_path / "cache"))
    assert "inside the data folder" in cache_inside_data(cfg)
    assert cache_inside_data(AppConfig(data=[tmp_path / "data"], disk_cache=DiskCacheConfig(directory=tmp_path / "cache"))) == ""


def test_the_key_covers_every_module_a_cached_step_can_depend_on():
    import re

    from app.disk_cache import KEYED_SOURCES, ROOT, keyed_files

    files = keyed_files()
    assert any(f.name == "tracker.py" for f in files) and any(f.name == "tracker_engine.py" for f in files)
    keyed = {f.relative_to(ROOT).as_posix() for f in files}
    for f in files:
        for mod in re.findall(r"^\s*(?:from|import)\s+((?:evpose|app)(?:\.\w+)*)", f.read_text(), re.M):
            parts = mod.split(".")
            covered = any(k in keyed for k in ("/".join(parts) + ".py", "/".join(parts) + "/__init__.py")) or any(
                mod.replace(".", "/").startswith(src) for src in KEYED_SOURCES if not src.endswith(".py"))
            assert covered, f"{f.relative_to(ROOT)} imports {mod}, which the disk cache key does not hash"


def test_chunks_a_catch_up_passed_are_written_once_their_frames_are_filled_in(squares_scene, tmp_path, pair_files):
    rec, cmap = squares_scene
    conf = DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=20)
    first = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0), disk=_maker(conf, pair_files))
    first.step()
    t = first.session.t0_us + 71 * first.session.dt_us
    while not first.catch_up(t, 50):
        pass
    first.seek_near(t)
    assert sorted(first.disk.written) == []  # chunks 0..2 lack the grid frames the catch-up skipped
    _run_ahead(first)
    assert sorted(first.disk.written) == list(range((first.n_steps + 19) // 20))
    second = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0), disk=_maker(conf, pair_files))
    assert second.ready_steps == first.n_steps and sorted(second.cache._frames) == list(range(0, first.n_steps, 5))
