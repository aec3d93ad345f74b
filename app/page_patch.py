"""Patches of viser's page: blob URLs of images revoked late (image probes never fail), hover help over labels too.

viser's image component (client ``components/Image.tsx``) makes a blob URL for each image it gets, shows it, and
starts a probe of its natural size (``new Image().src = url``); it revokes the URL when the next image comes or the
component unmounts (its panel moved, hidden, or the tab's GUI rebuilt). When the page is busy (software WebGL drawing
the 3D scene, a tab just opened, a layout switch redrawing the 3D view), the probe had not loaded by then, and the
console filled with "Failed to load resource: net::ERR_FILE_NOT_FOUND" (harmless: the image shown is always the latest).
Session 27 (/tmp/s27/ui27/a13e.py, c1_walk.py): every failure was the probe, never a shown ``<img>``; 4-5 per layout
switch while playing with a busy page (session 26's a13c), 5 in a tab opened while another stepped.

The cause is in viser's client, which the app cannot change, and the server cannot know when a tab's probe has loaded
(holding image sends around panel moves until every tab had answered a round trip removed most, not all: a probe made
by an image that came after the move still failed). So the page is told to revoke blob URLs REVOKE_DELAY_MS later:
a hidden 1x1 image in the main panel whose ``onload`` wraps ``URL.revokeObjectURL`` (viser renders its HTML elements
with innerHTML, where inline handlers run; ``window.URL`` by name: inside an inline handler a bare ``URL`` is
``document.URL``, a string). Memory: the few images of the last REVOKE_DELAY_MS stay in the browser
(tens of kB each). Revocation by viser's other code (file downloads) is delayed the same way, harmlessly.

**Hover help over a control's label** (session 28). viser (client ``components/common.tsx``, ``Checkbox.tsx``) wraps
only a control's *input* in the Mantine tooltip that shows its ``hint``; its label, where the eye and the pointer go
first, showed nothing (session 27's leftover: "mode", "rate [Hz]" and every parameter explained only over the slider
or box). A second hidden image's ``onload`` installs one document ``mouseover`` listener: over a label (a
``label[for]`` in the first column of viser's label/input row) it sends the tooltip's reference element (the box the
tooltip wraps around the input) a ``mouseenter`` (floating-ui's hover hook listens for that native event), and a
``mouseleave`` when the pointer leaves the label again. So the same tooltip opens, after the same 500 ms delay, over
the label as over the input; controls without a hint get nothing (their box has no listener).
``tests/app/test_server_browser.py`` hovers a label in Chromium and finds the hint (it would catch a viser client
that changes this structure).

**Number boxes keep showing their value** (session 31, /tmp/s31/fuzz31/gui/fuzz.py). viser's number boxes (a
slider's companion box, a plain number input) ignore text that is no finite number ("", "abc", "nan", "inf", " ") and
send nothing, rightly, but Mantine's box went on showing that text after the focus left it: the speed box read empty
while the player ran at 1.0x, a parameter's box empty while the tracker used 200 Hz, until the value next changed.
A third hidden image installs capture-phase ``focusin`` / ``input`` / ``focusout`` listeners that remember a box's last
finite text and put it back when the focus leaves the box holding something else (display only: no event is sent, so
the server sees nothing, as before). ``tests/app/test_server_browser_params.py`` types such text in Chromium.
"""

from __future__ import annotations

REVOKE_DELAY_MS = 3000
"""Delay of every blob URL revocation in the page, milliseconds (a busy page's probe loaded within ~1.5 s, a13e)."""

_GIF_1PX = "data:image/gif;base64,R0lGODlhAQABAIAAAAAAAP///yH5BAEAAAAALAAAAAABAAEAAAIBRAA7"

PAGE_PATCH_HTML = (
    f'<img alt="" src="{_GIF_1PX}" style="display:none" onload="if (!window.__evposeLateRevoke) {{'
    f" window.__evposeLateRevoke = true; const U = window.URL, revoke = U.revokeObjectURL.bind(U);"
    f" U.revokeObjectURL = (url) => setTimeout(() => revoke(url), {REVOKE_DELAY_MS}); }}\">"
)
"""The HTML element that patches the page (added once to the main panel)."""


LABEL_HINTS_JS = (
    "if (!window.__evposeLabelHints) { window.__evposeLabelHints = true; let shown = null;"
    " const refOf = (t) => { if (!(t instanceof Element)) return null;"
    " const l = t.closest('label[for]') || t.querySelector(':scope > label[for], :scope > p > label[for]');"
    " const row = l ? l.closest('.mantine-Flex-root') : null;"
    " if (!row || row.children.length < 2 || !row.children[0].contains(l)) return null;"
    " return row.children[1].firstElementChild; };"
    " document.addEventListener('mouseover', (e) => { const ref = refOf(e.target); if (ref === shown) return;"
    " if (shown) shown.dispatchEvent(new MouseEvent('mouseleave'));"
    " shown = ref; if (ref) ref.dispatchEvent(new MouseEvent('mouseenter')); }); }"
)
"""Installs the label hover (see the module docstring); single quotes only, it sits in a double-quoted attribute."""

LABEL_HINTS_HTML = f'<img alt="" src="{_GIF_1PX}" style="display:none" onload="{LABEL_HINTS_JS}">'
"""The HTML element that installs the label hover (added once to the main panel)."""


BOX_RESTORE_JS = (
    "if (!window.__evposeBoxRestore) { window.__evposeBoxRestore = true; const last = new WeakMap();"
    " const isBox = (t) => t instanceof HTMLInputElement && t.classList.contains('mantine-NumberInput-input');"
    " const finite = (s) => s.trim() !== '' && Number.isFinite(Number(s.trim()));"
    " const keep = (e) => { if (isBox(e.target) && finite(e.target.value)) last.set(e.target, e.target.value); };"
    " document.addEventListener('focusin', keep, true); document.addEventListener('input', keep, true);"
    " document.addEventListener('focusout', (e) => { const t = e.target;"
    " if (!isBox(t) || finite(t.value) || !last.has(t)) return;"
    " setTimeout(() => { if (document.activeElement !== t && !finite(t.value)) t.value = last.get(t); }, 0); }, true); }"
)
"""Installs the number boxes' restore (see the module docstring); single quotes only. The restore waits for the
box's own blur handling (a timeout of 0), which would otherwise render the typed text again over it."""

BOX_RESTORE_HTML = f'<img alt="" src="{_GIF_1PX}" style="display:none" onload="{BOX_RESTORE_JS}">'
"""The HTML element that installs the number boxes' restore (added once to the main panel)."""


def add_page_patch(gui):
    """Add the patches to the GUI (every tab that connects runs them once)."""
    gui.add_html(LABEL_HINTS_HTML)
    gui.add_html(BOX_RESTORE_HTML)
    return gui.add_html(PAGE_PATCH_HTML)
