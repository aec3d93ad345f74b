"""``evpose app``: the browser-based viewer (viser)."""

from __future__ import annotations

import time
from pathlib import Path


def main(
    data: list[Path] = [Path("demo_data"), Path("maps")],  # noqa: B006 - tyro reads the default
    host: str = "127.0.0.1",
    port: int = 8080,
    layout: str = "debug",
    export_dir: Path = Path("evpose_exports"),
) -> int:
    """Start the browser-based viewer: browse, play, step and tune the tracker on recordings and maps.

    Args:
        data: Folders searched for recordings (*.h5, bags, ECD folders) and maps (*_map.ply, *_cloud.ply); nothing outside them is opened.
        host: Interface to listen on; localhost by default.
        port: TCP port; the command fails with a clear message if it is taken.
        layout: Layout name from layouts/ (debug, teaching, compare, or one you saved).
        export_dir: Folder for exported trajectories, configurations, screenshots and GIFs.
    """
    from app.server import AppConfig, ViewerApp

    viewer = ViewerApp(AppConfig(data=list(data), host=host, port=port, layout=layout, export_dir=export_dir))
    print(f"evpose app: serving http://{host}:{port} (Ctrl+C to stop)", flush=True)
    try:
        while True:
            time.sleep(3600)
    finally:
        viewer.stop()
