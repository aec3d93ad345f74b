"""What the viewer's browser tests share: a free port, a viewer on a data folder, and a headless Chromium page on it
(Debian's chromium driven by Playwright), plus small waits and clicks."""

from __future__ import annotations

import contextlib
import time

from app.bench import CHROMIUM_ARGS, free_port


@contextlib.contextmanager
def running_viewer(tmp_path_factory, root, **config):
    """A :class:`ViewerApp` on ``root`` at a free port, exports in a temporary folder; stopped on exit."""
    from app.server import AppConfig, ViewerApp

    app = ViewerApp(AppConfig(data=[root], port=free_port(), export_dir=tmp_path_factory.mktemp("exports"), **config))
    try:
        yield app
    finally:
        app.stop()


@contextlib.contextmanager
def viewer_page(viewer):
    """A 1400x900 headless Chromium page on ``viewer``, once its panels have been drawn."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=CHROMIUM_ARGS)
        try:
            pg = browser.new_page(viewport={"width": 1400, "height": 900})
            pg.goto(f"http://127.0.0.1:{viewer.cfg.port}")
            pg.get_by_text("SP-TS positive").first.wait_for(timeout=30_000)
            yield pg
        finally:
            browser.close()


@contextlib.contextmanager
def console_errors(page):
    """The texts of the console errors the page logs while the block runs (a list, filled as they come)."""
    errors = []

    def on_console(msg):
        if msg.type == "error":
            errors.append(msg.text)

    page.on("console", on_console)
    try:
        yield errors
    finally:
        page.remove_listener("console", on_console)


def wait_for(cond, timeout=40.0, what="condition", detail=None):
    end = time.time() + timeout
    while time.time() < end:
        if cond():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}" + (f" ({detail()})" if detail else ""))


def choose(page, label, option):
    page.get_by_label(label, exact=True).click()
    page.get_by_role("option", name=option, exact=True).click()
