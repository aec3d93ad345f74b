"""Holding image sends back while panels holding images move, so the browser console stays clean.

Why (session 27, /tmp/s27/ui27/a13e.py on the demo data): moving or hiding a panel unmounts its images in the browser,
and viser's image component (client ``components/Image.tsx``) then revokes the blob URL of its image. That component
also starts a probe of the image's natural size (``new Image().src = url``) each time an image arrives; if the panel
moves before the probe has loaded, the probe fails with "Failed to load resource: net::ERR_FILE_NOT_FOUND" (harmless:
the image shown is always the latest; only the console fills). While playing, images arrive every drawn step and the
browser handles its messages once per animation frame, so a move one frame after an image hit a pending probe: 4-5
errors per layout switch with a busy page (session 26's a13c), none when paused or when the panels stayed put.
The same happens the other way round: a moved panel's images mount anew, each with a new probe, while the browser
redraws its resized 3D view; the next image sent (the next step played) revoked those (a13e: errors 20-90 ms after the
URL was made, 4 per move of the images panel, with the hold before the move alone). Nothing in the app can make
viser's probe load sooner or keep a moved image mounted, so image sends stop around a panel move until no probe can be
pending: every tab answers a round trip (its answer comes after it has handled every message sent before), the probes
get SETTLE_S to load, the panels move, the same again for the remounted images, then the step shown is sent again.
"""

from __future__ import annotations

import contextlib
import threading
import time
from typing import Callable, Iterator

ROUND_TRIP_TIMEOUT_S = 2.0
"""Longest wait for the tabs' round trip, seconds (a tab busy longer, or gone, is not waited for further)."""
SETTLE_S = 0.25
"""Time the browser gets after its round trip to load the probes of the images it got just before, seconds."""
_SYNC_KEY = "evpose-sync"


def wait_for_tabs(server, timeout_s: float = ROUND_TRIP_TIMEOUT_S) -> int:
    """Return once every connected tab has handled every message sent to it before (or the timeout); tabs answered."""
    deadline = time.monotonic() + timeout_s
    answered = 0
    for client in list(server.get_clients().values()):
        left = deadline - time.monotonic()
        if left <= 0:
            break
        try:
            client.local_storage.get_item(_SYNC_KEY, timeout=left)  # a read: answered in order, after the images
            answered += 1
        except (RuntimeError, TimeoutError):  # gone, busy past the timeout, or localStorage blocked
            pass
    return answered


class ImageHold:
    """Whether image sends are held back now; held steps are drawn again once the hold ends."""

    def __init__(self, server, redraw: Callable[[], None]):
        self._server = server
        self._redraw = redraw
        self.lock = threading.Lock()
        """Taken while a step's images are sent, so a hold starts between two steps' sends, never within one."""
        self._holds = 0
        self._skipped = False

    def images_allowed(self) -> bool:
        """Call with ``lock`` held: False while held (the step's images are then left out and sent after the hold)."""
        if self._holds:
            self._skipped = True
        return not self._holds

    def _settle(self) -> None:
        if self._server.get_clients() and wait_for_tabs(self._server):
            time.sleep(SETTLE_S)

    @contextlib.contextmanager
    def quiet(self) -> Iterator[None]:
        """Hold image sends, wait until every tab has loaded the images sent before, run the body, send the step again."""
        with self.lock:
            self._holds += 1
        try:
            self._settle()  # the images sent before have loaded: nothing pending to unmount
            with self._server.atomic():  # all moves in one message batch: no panel mounted at a place on the way
                yield
            self._settle()  # the moved panels' images (mounted anew, each with its probe) have loaded
        finally:
            with self.lock:
                self._holds -= 1
                redraw = not self._holds and self._skipped
                if redraw:
                    self._skipped = False
            if redraw:
                self._redraw()
