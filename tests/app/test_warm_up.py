"""The warm-up prepares recordings before they are opened: a fresh player's far seek then reads its pose from the disk
cache, equal to a headless run; prepared recordings are skipped, unreadable ones reported, the open one deferred."""

import queue
import signal
import socket
import threading

import numpy as np
import pytest

from app.browser import DataEntry, DataRoots, EntryKind, load_map, load_recording
from app.disk_cache import DiskCacheConfig
from app.engine_factory import engine_factory
from app.frame_cache import FrameCacheConfig
from app.player import Player, PlayerConfig
from app.server import AppConfig, ViewerApp
from app.warm_up import OPEN_NOTE, PREPARED, WarmUp, _worker
from evpose.io.h5 import write_recording_h5
from evpose.io.map_ply import write_contour_map
from evpose.tracker.session import TrackingSession


@pytest.fixture(scope="module")
def data_root(tmp_path_factory, squares_scene):
    from app_scenes import map_scene

    root = tmp_path_factory.mktemp("data")
    rec, cmap = squares_scene
    write_recording_h5(root / "squares.h5", rec)
    write_recording_h5(root / "squares_other.h5", map_scene(seed=1, speed=3.0)[0])
    write_contour_map(root / "squares_map.ply", cmap)
    (root / "corrupt.h5").write_bytes(b"\x89HDF\r\n\x1a\n broken")
    return root


def _entries(root):
    return DataRoots([root]).scan()


def _run_worker(entries, disk, open_path=None, jobs=None):
    """The warm-up process's loop, in this process (no niceness change); {label: last state}."""
    commands, reports = queue.Queue(), queue.Queue()
    jobs = jobs if jobs is not None else [e for e in entries if e.kind == EntryKind.RECORDING and e.error is None]
    # In the main thread the worker ignores Ctrl+C as its own process does: the rest of the test run must not.
    sigint = signal.getsignal(signal.SIGINT)
    try:
        _worker(jobs, [e for e in entries if e.kind == EntryKind.MAP], open_path, disk, FrameCacheConfig(), commands, reports, nice=0)
    finally:
        signal.signal(signal.SIGINT, sigint)
    states = {}
    while (msg := reports.get_nowait()) is not None:
        states[msg[0]] = msg[1]
    return states


def _pair(root, name):
    return root / f"{name}.h5", root / "squares_map.ply"


def test_the_viewers_warm_up_prepares_the_unopened_recording_and_a_fresh_players_far_seek_reads_it_from_disk(data_root, tmp_path):
    disk = DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=20)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    app = ViewerApp(AppConfig(data=[data_root], port=port, export_dir=tmp_path / "exports", disk_cache=disk, warm_up=True,
                              player=PlayerConfig(prefetch=False)))
    try:
        assert app.warm_up.wait(0.0) is False  # running in its own process while the viewer serves
        assert app.select(next(e.label for e in app.entries if e.path.name == "squares.h5"))
        other = next(e for e in app.entries if e.path.name == "squares_other.h5")
        deadline = threading.Event()
        for _ in range(600):
            if app.warm_up.states.get(other.label, "").startswith(PREPARED):
                break
            deadline.wait(0.2)
        squares = next(e for e in app.entries if e.path.name == "squares.h5")
        assert app.warm_up.states[other.label].startswith(PREPARED), app.warm_up.states
        assert app.warm_up.states[squares.label] == OPEN_NOTE  # left to the player's own run-ahead
        assert "corrupt.h5" not in app.warm_up.states  # listed as unreadable by the browser already
        # Once every recording is settled the list is one line (it pushed the folders below it off the screen).
        assert app.warm_info.content.startswith("**Prepared for seeking:** 2 recordings"), app.warm_info.content
        assert "\n-" not in app.warm_info.content
        # The viewer itself, opening the prepared recording, reads every step back.
        assert app.select(other.label)
        n = app.player.call(lambda e: (e.disk_steps, e.n_steps)).result(60)
        assert n[0] == n[1] > 0
    finally:
        app.stop()
    rec_path, map_path = _pair(data_root, "squares_other")
    rec, cmap = load_recording(rec_path), load_map(map_path)
    frames = []
    p = Player(engine_factory(rec, cmap, "tracking", FrameCacheConfig(), disk, (rec_path, map_path)),
               lambda f, e: frames.append(f), player_config=PlayerConfig(prefetch=False))
    try:
        headless = TrackingSession(rec, cmap)
        n_steps = p.engine.n_steps
        ref = [headless.step(debug=False) for _ in range(n_steps)]
        t = ref[int(0.9 * n_steps)].t_us
        p.seek(t)
        assert p.wait_idle(60)
        f = frames[-1]
        assert not f.preview and f.index >= int(0.9 * n_steps) - p.engine.cache.every
        assert p.call(lambda e: (e.frontier, e.session.step_count)).result(60) == (0, 0)  # nothing was tracked
        assert np.array_equal(f.pose, ref[f.index].pose) and f.status == ref[f.index].status.value
        hist = p.call(lambda e: e.history).result(60)
        assert all(np.array_equal(s.pose, r.pose) for s, r in zip(hist, ref))
    finally:
        p.stop()


def test_recordings_already_prepared_are_skipped(data_root, tmp_path):
    disk = DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=20)
    entries = _entries(data_root)
    first = _run_worker(entries, disk)
    assert all(v.startswith(PREPARED) and "computed" in v for k, v in first.items() if "squares" in k), first
    chunks = sorted((tmp_path / "cache").rglob("chunk_*.pkl"))
    stamps = [c.stat().st_mtime_ns for c in chunks]
    second = _run_worker(entries, disk)
    assert all("found in the disk cache" in v for k, v in second.items() if "squares" in k), second
    assert sorted((tmp_path / "cache").rglob("chunk_*.pkl")) == chunks and [c.stat().st_mtime_ns for c in chunks] == stamps


def test_an_unreadable_recording_is_reported_and_the_warm_up_goes_on(data_root, tmp_path):
    bad = tmp_path / "truncated.h5"
    bad.write_bytes((data_root / "squares.h5").read_bytes()[:4096])  # probed fine as a name, fails to load
    entries = _entries(data_root)
    jobs = [DataEntry(EntryKind.RECORDING, bad, "x/truncated.h5")] + [e for e in entries if e.path.name == "squares.h5"]
    states = _run_worker(entries, DiskCacheConfig(directory=tmp_path / "cache"), jobs=jobs)
    assert states["x/truncated.h5"].startswith("failed: ")
    assert states[jobs[1].label].startswith(PREPARED)


def test_a_recording_without_calibration_is_reported_by_its_problem_without_repeating_its_path(data_root, tmp_path, squares_scene):
    import dataclasses

    rec = tmp_path / "squares_no_calib.h5"
    write_recording_h5(rec, dataclasses.replace(squares_scene[0], calibration=None))
    entries = _entries(data_root)
    jobs = [DataEntry(EntryKind.RECORDING, rec, "x/squares_no_calib.h5")]
    states = _run_worker(entries, DiskCacheConfig(directory=tmp_path / "cache"), jobs=jobs)
    assert states["x/squares_no_calib.h5"] == ("failed: tracking cannot start: the recording has no camera calibration; "
                                              "tracking needs intrinsics")


def test_the_open_recording_is_deferred_until_another_is_opened(data_root, tmp_path):
    disk = DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=20)
    entries = _entries(data_root)
    jobs = [e for e in entries if e.kind == EntryKind.RECORDING and e.error is None]
    opened = next(e for e in jobs if e.path.name == "squares.h5")
    commands, reports = queue.Queue(), queue.Queue()
    maps = [e for e in entries if e.kind == EntryKind.MAP]
    t = threading.Thread(target=_worker, args=(jobs, maps, opened.path, disk, FrameCacheConfig(), commands, reports, 0))
    t.start()
    seen = []
    while not any(m and m[1].startswith(PREPARED) for m in seen):
        seen.append(reports.get(timeout=120))
    assert (opened.label, OPEN_NOTE) in seen and not any(m[0] == opened.label and m[1].startswith(PREPARED) for m in seen)
    commands.put(("open", None))  # the user opened nothing (or another recording): its turn comes
    t.join(120)
    while (m := reports.get_nowait()) is not None:
        seen.append(m)
    assert seen[-1][0] == opened.label and seen[-1][1].startswith(PREPARED)


def test_the_warm_up_is_off_with_its_switch_and_with_the_disk_cache(data_root, tmp_path):
    shown = []
    for w in (WarmUp(DiskCacheConfig(directory=tmp_path / "c"), FrameCacheConfig(), shown.append, enabled=False),
              WarmUp(DiskCacheConfig(enabled=False, directory=tmp_path / "c"), FrameCacheConfig(), shown.append)):
        w.start(_entries(data_root))
        assert not w.enabled and w._proc is None and w.wait(0.0) and w.markdown() == ""
    assert shown == ["", ""] and not (tmp_path / "c").exists()
    assert AppConfig().warm_up is False  # viewers made in code start no process unless asked


def test_evpose_app_prepare_fills_the_cache_for_a_recording_and_guesses_its_map(data_root, tmp_path, capsys):
    from evpose.cli.main import run

    cache = tmp_path / "cache"
    assert run(["app", "--prepare", str(data_root / "squares.h5"), "--data", str(data_root), "--cache-dir", str(cache)]) == 0
    out = capsys.readouterr().out
    assert "squares_map.ply" in out and "computed in" in out
    rec_path, map_path = _pair(data_root, "squares")
    rec = load_recording(rec_path)
    eng = engine_factory(rec, load_map(map_path), "tracking", None, DiskCacheConfig(directory=cache), (rec_path, map_path))(None)
    assert eng.disk_steps == eng.n_steps
    assert run(["app", "--prepare", str(data_root / "squares.h5"), "--data", str(data_root), "--cache-dir", str(cache)]) == 0
    assert "already in the disk cache" in capsys.readouterr().out
    assert run(["app", "--prepare", str(data_root / "squares.h5"), "--data", str(data_root), "--no-disk-cache"]) == 2


def test_evpose_app_prepare_with_a_map_no_update_registers_against_is_a_one_line_error_naming_the_map(data_root, tmp_path, capsys):
    import dataclasses

    from evpose.cli.main import run

    cmap = load_map(data_root / "squares_map.ply")
    n = 300  # a patch of edgeless ground under the start pose: in view, but not this scene's map
    patch = np.c_[np.random.default_rng(0).uniform(-0.04, 0.04, (n, 2)), np.full(n, cmap.points[:, 2].mean())]
    wrong = dataclasses.replace(cmap, points=patch, **{k: getattr(cmap, k)[:n] for k in
                                                       ("edge_normal", "plane_normal", "region_id", "curvature", "brightness_sign")})
    write_contour_map(tmp_path / "wrong_map.ply", wrong)
    args = ["app", "--prepare", str(data_root / "squares.h5"), "--map", str(tmp_path / "wrong_map.ply"), "--cache-dir", str(tmp_path / "cache")]
    capsys.readouterr()
    assert run([*args, "--acquire-s", "0.05"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert (f"{tmp_path / 'wrong_map.ply'}: updates 1-25: no update registered against this map in the first 0.12 s of squares.h5:"
            " is it this recording's map, in its frame?") in err
    assert run([*args, "--acquire-s", "0"]) == 0  # 0 = never give up: the pairing is prepared, as the viewer shows it


def test_evpose_app_prepare_refuses_a_map_registering_only_by_chance_under_dense_events(tmp_path, capsys):
    import dataclasses

    from app_scenes import map_scene
    from evpose.cli.main import run
    from evpose.core.events import EventArray

    rec, cmap = map_scene()
    # 5e5 noise events/s over 160x120 (26 per pixel per second): the edgeless patch registers 43 of 93 updates.
    e, rng, m = rec.events, np.random.default_rng(1), 250_000
    t, x, y, p = (np.r_[e.t, rng.integers(e.t[0], e.t[-1], m)], np.r_[e.x, rng.integers(0, 160, m)],
                  np.r_[e.y, rng.integers(0, 120, m)], np.r_[e.p, rng.choice([-1, 1], m)])
    o = np.argsort(t, kind="stable")
    write_recording_h5(tmp_path / "noisy.h5", dataclasses.replace(rec, events=EventArray.from_arrays(t[o], x[o], y[o], p[o])))
    write_contour_map(tmp_path / "map.ply", cmap)
    n = 300
    patch = np.c_[np.random.default_rng(0).uniform(-0.04, 0.04, (n, 2)), np.full(n, cmap.points[:, 2].mean())]
    wrong = dataclasses.replace(cmap, points=patch, **{k: getattr(cmap, k)[:n] for k in
                                                       ("edge_normal", "plane_normal", "region_id", "curvature", "brightness_sign")})
    write_contour_map(tmp_path / "wrong_map.ply", wrong)
    capsys.readouterr()
    assert run(["app", "--prepare", str(tmp_path / "noisy.h5"), "--map", str(tmp_path / "wrong_map.ply"), "--cache-dir",
                str(tmp_path / "cache")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"{tmp_path / 'wrong_map.ply'}: updates 1-" in err and "than chance" in err
    assert run(["app", "--prepare", str(tmp_path / "noisy.h5"), "--map", str(tmp_path / "map.ply"), "--cache-dir",
                str(tmp_path / "cache")]) == 0


def _chunk_contents(folder):
    """Every chunk of the one entry under ``folder``, without the wall-clock timings (they differ run to run)."""
    import pickle

    (entry,) = [d for d in folder.iterdir() if d.is_dir()]
    out = []
    for path in sorted(entry.glob("chunk_*.pkl")):
        with open(path, "rb") as f:
            chunk = pickle.load(f)
        summaries = [pickle.dumps({k: v for k, v in vars(s).items() if k != "timings_ms"}) for s in chunk["summaries"]]
        frames = {k: (size, {n: pickle.dumps(v) for n, v in fields.items() if n != "timings_ms"})
                  for k, (size, fields) in chunk["frames"].items()}
        out.append((path.name, summaries, frames))
    return entry.name, out


def test_the_warm_up_writes_the_same_entry_as_the_players_own_run_ahead(data_root, tmp_path):
    rec_path, map_path = _pair(data_root, "squares")
    entries = [e for e in _entries(data_root) if e.kind == EntryKind.MAP or e.path == rec_path.resolve()]
    assert _run_worker(entries, DiskCacheConfig(directory=tmp_path / "warm", chunk_steps=20))
    disk = DiskCacheConfig(directory=tmp_path / "player", chunk_steps=20)
    rec, cmap = load_recording(rec_path), load_map(map_path)
    p = Player(engine_factory(rec, cmap, "tracking", FrameCacheConfig(), disk, (rec_path.resolve(), map_path.resolve())),
               lambda f, e: None)
    try:
        p.seek(rec.t_start_us)
        for _ in range(1200):
            if p.call(lambda e: len(e.disk.written) * e.disk.chunk_steps >= e.n_steps).result(60):
                break
            threading.Event().wait(0.1)
    finally:
        p.stop()
    warm, played = _chunk_contents(tmp_path / "warm"), _chunk_contents(tmp_path / "player")
    assert warm[0] == played[0] and len(warm[1]) == len(played[1]) > 1  # same key: same recording, map, configuration
    assert warm == played


def test_a_nearly_full_disk_cache_stops_the_warm_up_from_pushing_out_watched_recordings(data_root, tmp_path):
    disk = DiskCacheConfig(directory=tmp_path / "cache", budget_mb=64.0)
    watched = tmp_path / "cache" / "watched"
    watched.mkdir(parents=True)
    (watched / "meta.json").write_text("{}")
    (watched / "chunk_00000.pkl").write_bytes(b"x" * int(0.85 * 64 * 2**20))
    states = _run_worker(_entries(data_root), disk)
    assert states and all(v.startswith("not prepared: the disk cache is 80 % full") for v in states.values()), states
    assert sorted(p.name for p in (tmp_path / "cache").iterdir()) == ["watched"]


def test_the_warm_up_holds_still_while_the_player_plays_or_computes_a_seek(data_root, tmp_path):
    busy = threading.Event()
    busy.set()
    w = WarmUp(DiskCacheConfig(directory=tmp_path / "cache", chunk_steps=20), FrameCacheConfig(), lambda md: None,
               busy=busy.is_set)
    squares = [e for e in _entries(data_root) if e.kind == EntryKind.MAP or e.path.name == "squares.h5"]
    try:
        w.start(squares)
        assert not w.wait(4.0)  # long enough for the process to start and prepare it, were it not held
        assert set(w.states.values()) == {"queued"} and not (tmp_path / "cache").exists()
        busy.clear()  # the player paused: the warm-up goes on
        assert w.wait(120) and all(v.startswith(PREPARED) for v in w.states.values()), w.states
    finally:
        w.stop()


def test_the_player_is_busy_while_it_runs_ahead_or_plays_and_idle_once_done(squares_scene):
    from app.tracker_engine import TrackerEngine

    rec, cmap = squares_scene
    p = Player(lambda cfg: TrackerEngine(rec, cmap, cfg), lambda f, e: None)
    try:
        p.seek(rec.t_start_us)
        assert p.call(lambda e: p.busy).result(60)  # the run-ahead has the whole recording to do
        for _ in range(1200):
            if not p.call(lambda e: p.busy).result(60):
                break
            threading.Event().wait(0.05)
        assert p.call(lambda e: e.frontier >= e.n_steps).result(60) and not p.busy
        p.seek(rec.t_start_us)
        assert p.wait_idle(60)
        p.play()
        assert p.call(lambda e: p.busy).result(60)
    finally:
        p.stop()


def test_the_list_of_prepared_recordings_is_one_line_once_all_are_settled():
    # A line or two per recording pushed the 3D view, Layout and Export folders below a 900 px screen for good.
    from app.warm_up import WarmUp

    w = WarmUp(None, None, lambda md: None)
    w.states = {"a.h5": "preparing 40 %", "b.h5": PREPARED, "c.h5": OPEN_NOTE, "d.h5": "no map found: events only, nothing to prepare"}
    assert "- `a.h5`: preparing 40 %" in w.markdown()
    w.states["a.h5"] = PREPARED
    assert w.markdown() == ("**Prepared for seeking:** 3 recordings, each with the map it opens with and the default "
                            "parameters (a seek anywhere there reads its pose from the disk cache); 1 without a map, "
                            "nothing to prepare.")
    w.states["a.h5"] = "failed: unreadable"
    assert "- `a.h5`: failed: unreadable" in w.markdown()
