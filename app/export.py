"""Exports from the viewer: trajectory (TUM), configuration (YAML), screenshot (PNG), short GIF of the 3D view."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from app.config_gui import save_config_file
from evpose.core.trajectory import Trajectory
from evpose.io.atomic import atomic_path


def tum_text(traj: Trajectory) -> str:
    """TUM lines ``t tx ty tz qx qy qz qw`` (t in seconds, pose ``T_world_cam``)."""
    lines = [
        f"{t / 1e6:.6f} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} {q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}"
        for t, p, q in zip(traj.t, traj.position, traj.quat_xyzw)
    ]
    return "\n".join(lines) + ("\n" if lines else "")


def write_tum(traj: Trajectory, path: str | Path) -> Path:
    path = Path(path)
    try:
        from evpose.io.tum import write_tum as project_write_tum  # the IO layer's writer, when it exists
    except ImportError:
        project_write_tum = None
    if project_write_tum is not None:
        project_write_tum(path, traj)
        return path
    with atomic_path(path) as tmp:
        Path(tmp).write_text(tum_text(traj))
    return path


def write_config(config, path: str | Path) -> Path:
    save_config_file(config, path)
    return Path(path)


BACKGROUND_LIGHT = (255, 255, 255)
BACKGROUND_DARK = (16, 17, 19)
"""The 3D view's background in viser's light and dark themes (white; Mantine's dark[9])."""


def over_background(img: np.ndarray, background=BACKGROUND_LIGHT) -> np.ndarray:
    """An RGB image of ``img``; an RGBA one is composited over ``background`` (a PNG render has a transparent
    background: its alpha dropped, the exported view came out black behind a white grid)."""
    img = np.asarray(img)
    if img.ndim != 3 or img.shape[2] != 4:
        return np.ascontiguousarray(img[..., :3])
    a = img[..., 3:4].astype(np.float32) / 255.0
    out = img[..., :3].astype(np.float32) * a + np.asarray(background, np.float32) * (1.0 - a)
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def write_png(rgb: np.ndarray, path: str | Path, background=BACKGROUND_LIGHT) -> Path:
    import imageio.v3 as iio

    path = Path(path)
    with atomic_path(path) as tmp:
        iio.imwrite(tmp, over_background(rgb, background), extension=".png")
    return path


def write_gif(frames: list[np.ndarray], path: str | Path, fps: float = 10.0) -> Path:
    import imageio.v3 as iio

    if not frames:
        raise ValueError("no frames to write")
    path = Path(path)
    with atomic_path(path) as tmp:
        iio.imwrite(tmp, np.stack([f[..., :3] for f in frames]), extension=".gif", duration=1000.0 / fps, loop=0)
    return path


def stamped_name(stem: str, suffix: str) -> str:
    """``stem-YYYYmmdd-HHMMSS.suffix`` so repeated exports never overwrite each other."""
    return f"{stem}-{time.strftime('%Y%m%d-%H%M%S')}{suffix}"


def _render_client(app, client):
    if client is None:
        clients = list(app.server.get_clients().values())
        if not clients:
            raise ValueError("a screenshot needs a connected browser")
        client = clients[0]
    return client


def _render(client, **kwargs) -> np.ndarray:
    """One render of the 3D view by ``client``'s browser. Its tab closed meanwhile: ValueError (viser's RuntimeError
    was a traceback on the server's console, and every other tab kept reading "rendering a 16-frame GIF...")."""
    try:
        return client.get_render(**kwargs)
    except RuntimeError as exc:
        raise ValueError(f"the browser tab rendering it went away ({exc})") from None


def export_action(app, what: str, client=None, gif_frames: int = 16) -> Path:
    """Run one export of the viewer ``app``: 'trajectory', 'config', 'screenshot' or 'GIF'; returns the file."""
    out_dir = Path(app.cfg.export_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if what == "trajectory":
        traj = app.player.call(lambda eng: eng.trajectory()).result(60)
        if len(traj) == 0:
            raise ValueError("no estimated poses yet (the events-only view tracks nothing)")
        return write_tum(traj, out_dir / stamped_name("trajectory", ".txt"))
    if what == "config":
        cfg = app.player.call(lambda eng: eng.config).result(60)
        return write_config(cfg, out_dir / stamped_name("config", ".yaml"))
    client = _render_client(app, client)
    # A render takes the browser a moment (a GIF: seconds); without a word the button looked like it did nothing.
    if what in ("screenshot", "GIF"):
        app.export_info.content = (f"_rendering a {gif_frames}-frame GIF in the browser (a few seconds)..._" if what == "GIF"
                                   else "_rendering the screenshot in the browser..._")
    if what == "screenshot":
        img = _render(client, height=540, width=960, transport_format="png", timeout=20.0)
        dark = app.layout is not None and app.layout.dark_mode
        return write_png(img, out_dir / stamped_name("screenshot", ".png"), BACKGROUND_DARK if dark else BACKGROUND_LIGHT)
    if what == "GIF":
        frames = []
        was_playing = app.player.state.value == "playing"
        shown, n = app.last_frame, getattr(app.player.engine, "n_steps", None)
        if not was_playing and shown is not None and n is not None:
            # Paused near the end, the steps forward ran out and the GIF was one still frame: it ends on the last step.
            for _ in range(max(0, shown.index + gif_frames - (n - 1))):
                app.player.step_back()
        for _ in range(gif_frames):
            if not was_playing:
                app.player.step_forward()
                app.player.wait_idle(10.0)
            frames.append(_render(client, height=270, width=480, transport_format="jpeg", timeout=20.0))
        if not was_playing and shown is not None:
            # Back to the step shown when the button was pressed: the GIF left the viewer 16 steps on, the moment a
            # lesson was looking at (or had just bookmarked) gone (session 29).
            app.player.seek(shown.t_us, exact=True)
        return write_gif(frames, out_dir / stamped_name("view", ".gif"), fps=8.0)
    raise ValueError(f"unknown export {what!r}")
