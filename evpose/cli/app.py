"""``evpose app``: the browser-based viewer (viser)."""

from __future__ import annotations

import math
import signal
import time
from pathlib import Path

from evpose.tracker.map_acquisition import DEFAULT_ACQUIRE_S


_DEFAULT_DATA = (Path("demo_data"), Path("maps"))


def default_data_folders(data: list[Path]) -> list[Path]:
    """The default ``--data`` resolved: ``demo_data`` and ``maps`` of the current folder when it has them, else the
    bundled ones of this checkout (so ``evpose app`` works from any folder); any other ``--data`` as given."""
    if tuple(data) != _DEFAULT_DATA or all(d.is_dir() for d in data):
        return list(data)
    bundled = [Path(__file__).resolve().parents[2] / d for d in _DEFAULT_DATA]
    return bundled if all(d.is_dir() for d in bundled) else list(data)


def check_arguments(data: list[Path], port: int, layout: str, export_dir: Path, cache_dir: Path | None) -> None:
    """Refuse what would otherwise start a server that cannot work as asked: a typo in ``--data`` served an empty
    browser, an unknown ``--layout`` a default one, and an out-of-range port ended in a bind() traceback."""
    import app.layouts
    from app.layouts import layout_path, load_layout

    from evpose.errors import InputError
    from evpose.io.atomic import check_outputs

    if not 0 <= port <= 65535:
        raise InputError(None, f"--port must be 0..65535, got {port}")
    for root in data:
        if not root.exists():
            raise InputError(root, "no such folder (--data takes folders of recordings and maps)")
        if not root.is_dir():
            raise InputError(root, "not a folder (--data takes folders of recordings and maps, not single files)")
    folder = app.layouts.LAYOUT_DIR
    path = layout_path(layout, folder)
    if not path.is_file():
        known = sorted(q.stem for q in folder.glob("*.json"))
        raise InputError(None, f"--layout {layout!r} is not in {folder} (known: {', '.join(known)})")
    load_layout(path)  # a broken saved layout served the default one, its error shown only in the browser
    check_outputs((), folders=(export_dir, cache_dir))


def warn_bookmarks(path: Path) -> None:
    """One line on stderr when the bookmarks file cannot be read. Not an error: a slip in a bookmark must not keep a
    teacher's viewer from starting (the Bookmarks folder names the problem too, and nothing is saved over the file)."""
    import sys

    from app.bookmarks import load_bookmarks

    from evpose.errors import EvposeError, one_line

    try:
        load_bookmarks(path)
    except EvposeError as exc:
        print(f"evpose app: warning: bookmarks not read: {one_line(str(exc))}", file=sys.stderr, flush=True)


def prepare_recording(recording: Path, map_path: Path | None, data: list[Path], cache, acquire_s: float = DEFAULT_ACQUIRE_S) -> int:
    """``evpose app --prepare``: fill the disk cache for ``recording`` (and its map) as the warm-up does, printing progress.

    A map no update registers against within ``acquire_s`` is an error (exit 2), not the viewer's warning: the
    viewer must go on showing what the tracker does with the pairing, but a preparation run is unattended (often a
    script over a folder, the map guessed from ``--data``), its only product is a cache of motion-model poses
    nobody asked for, and a warning scrolled past in its output would be missed. The steps computed until then
    stay in the cache; the viewer still opens the pairing (and warns)."""
    from app.browser import DataEntry, DataRoots, EntryKind, guess_map_for, load_recording
    from app.warm_up import prepare_pair

    from evpose.errors import InputError
    from evpose.io.atomic import check_outputs
    from evpose.io.map_ply import read_contour_map

    if not cache.enabled:
        raise InputError(None, "--prepare fills the disk cache: it cannot be used with --no-disk-cache")
    if not math.isfinite(acquire_s) or acquire_s < 0:  # -1 ran as 0 (never give up) silently
        raise InputError(None, f"--acquire-s must be a finite number of seconds >= 0 (0 = never give up), got {acquire_s}")
    check_outputs((), folders=(cache.folder(),))
    for p in (recording, map_path):
        if p is not None and not p.exists():
            raise InputError(p, "no such file")
    rec_path = recording.resolve()
    rec = load_recording(rec_path)
    if map_path is None:
        maps = [e for e in DataRoots([d for d in data if d.is_dir()]).scan() if e.kind == EntryKind.MAP]
        guess = guess_map_for(DataEntry(EntryKind.RECORDING, rec_path, rec_path.name), maps, rec.metadata)
        if guess is None:
            raise InputError(recording, "no map under --data matches it; give one with --map")
        map_path = guess.path
    map_path = map_path.resolve()
    print(f"evpose app: preparing {rec_path} with {map_path} into {cache.folder()}", flush=True)
    shown = [0]

    def progress(fraction: float) -> None:
        if int(fraction * 10) > shown[0]:
            shown[0] = int(fraction * 10)
            print(f"  {100 * fraction:.0f} %", flush=True)

    result = prepare_pair(rec, read_contour_map(map_path), (rec_path, map_path), cache, None, progress, acquire_s=acquire_s)
    how = f"computed in {result.seconds:.1f} s" if result.computed else "already in the disk cache"
    print(f"evpose app: prepared {result.steps} steps ({how})", flush=True)
    return 0



def _interrupt(signum, frame) -> None:
    """SIGTERM handler: unwind as Ctrl+C does."""
    raise KeyboardInterrupt


def main(
    data: list[Path] = [Path("demo_data"), Path("maps")],  # noqa: B006 - tyro reads the default
    host: str = "127.0.0.1",
    port: int = 8080,
    layout: str = "debug",
    export_dir: Path = Path("evpose_exports"),
    cache_dir: Path | None = None,
    disk_cache: bool = True,
    warm_up: bool = True,
    prepare: Path | None = None,
    map: Path | None = None,  # noqa: A002 - the option is --map
    acquire_s: float = DEFAULT_ACQUIRE_S,
    bookmarks: Path | None = None,
) -> int:
    """Start the browser-based viewer: browse, play, step and tune the tracker on recordings and maps.

    Args:
        data: Folders searched for recordings (*.h5, bags, ECD folders) and maps (*_map.ply, *_cloud.ply); nothing outside them is opened (default: demo_data and maps here, else the bundled ones).
        host: Interface to listen on; localhost by default.
        port: TCP port; the command fails with a clear message if it is taken.
        layout: Layout name from layouts/ (debug, teaching, compare, or one you saved).
        export_dir: Folder for exported trajectories, configurations, screenshots and GIFs.
        cache_dir: Where computed steps are kept between openings of the same recording, map, configuration and
            code (default ``$XDG_CACHE_HOME/evpose/viewer``, i.e. ``~/.cache/evpose/viewer``; never inside a data folder).
        disk_cache: Keep and reuse computed steps in the cache folder (``--no-disk-cache``: compute afresh, write nothing).
        warm_up: Prepare every recording under ``--data`` (with the map it opens with, default parameters) into the
            cache folder in the background at the lowest CPU priority, so a seek anywhere in it answers at once even
            before it was ever opened (``--no-warm-up``: only what the player computes is kept; off with ``--no-disk-cache``).
        prepare: Instead of serving, prepare this recording into the cache folder now (in the foreground) and exit.
        map: The contour map for ``--prepare`` (default: the one the viewer would open it with, from ``--data``).
        acquire_s: ``--prepare`` stops with an error, as ``evpose track`` does, if no update registers against the map
            within this many seconds of the start, or the registrations there are no better than chance (a wrong map;
            the viewer only warns, as it must show the pairing); 0 = never.
        bookmarks: The lesson bookmarks' file (default ``layouts/bookmarks/bookmarks.json``, beside the layouts); one
            that cannot be read is a one-line warning here and in the viewer's Bookmarks folder, and is never written over.
    """
    from app.disk_cache import DiskCacheConfig
    from app.server import AppConfig, ViewerApp

    data = default_data_folders(list(data))
    cache = DiskCacheConfig(enabled=disk_cache, directory=cache_dir)
    if prepare is not None:
        return prepare_recording(prepare, map, data, cache, acquire_s)
    check_arguments(data, port, layout, export_dir, cache_dir)
    cfg = AppConfig(data=list(data), host=host, port=port, layout=layout, export_dir=export_dir, disk_cache=cache,
                    warm_up=warm_up, bookmarks_file=bookmarks)
    warn_bookmarks(cfg.bookmarks_path())
    viewer = ViewerApp(cfg)
    print(f"evpose app: serving http://{host}:{port} (Ctrl+C to stop)", flush=True)
    # A service manager's SIGTERM stops the viewer as Ctrl+C does (the warm-up process and its queues shut down too).
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        while True:
            time.sleep(3600)
    finally:
        viewer.stop()
