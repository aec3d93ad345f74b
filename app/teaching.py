"""Plain-words explanations of each EV-Pose stage, filled with the live figures of the step on screen.

Session 28 (a teacher's pass over the teaching layout in headless Chromium, /tmp/s28/ux28/s_teacher.py): the stages
are walked with *previous / next* in the panel (:func:`stage_after`; the dropdown alone took two clicks and a search
per stage), the live image colours the map points as its stage explains them (:data:`STAGE_OVERLAY`), and the text
says which 3D elements it points at are hidden by the *3D view* checkboxes (:data:`SCENE_REFERENCES`). The live
image comes first, captioned (:func:`image_caption`), the text under it: on a 1280x720 projector the teaching
layout's panel (above the Images panel) showed the text and the image's top 10 px (/tmp/s28/ux28/s_proj.py); the
SP-TS stage's image holds both polarities, as its text does."""

from __future__ import annotations

import enum

import numpy as np

from app.frame import Frame
from app.frame_cache import unit
from app.panels import OverlayColour, tdf_image


class Stage(str, enum.Enum):
    """The stage the teaching panel explains."""

    EVENTS = "events"
    SP_TS = "SP-TS"
    TDF = "TDF"
    POLARITY = "polarity prediction"
    REGISTRATION = "registration"
    FUSION = "fusion"


EXPLANATIONS: dict[Stage, str] = {
    Stage.EVENTS: (
        "An event camera does not take pictures. Each pixel reports, on its own, the moment its brightness "
        "changes by a set amount: an **ON** event (red) when it gets brighter, **OFF** (blue) when darker. "
        "Moving edges therefore light up as thin lines of events. A noise filter throws away lonely events "
        "whose neighbours stayed silent, and in mode `full` the ego-motion filter (off by default, `ego motion > enabled`) events "
        "that do not fit the camera's own motion (both grey in the *events kept / removed* panel)."
    ),
    Stage.SP_TS: (
        "The **separated-polarity time surface** keeps, for every pixel, the time of its latest ON event and, "
        "separately, of its latest OFF event. Shown as `exp(-age / eta)`: a pixel that just fired is bright, and "
        "it fades as time passes. The result looks like an edge with a comet tail behind it: the tail points "
        "back along the way the edge came."
    ),
    Stage.TDF: (
        "The **temporal distance field** is `1 - time surface`: near 0 exactly on the newest edge, growing behind "
        "it, then slightly blurred (`distance field > blur [px]`). It acts as a landscape of valleys along the edges. "
        "The contour map points are projected into it "
        "from the current pose guess; each point's height in the landscape is its *residual*."
    ),
    Stage.POLARITY: (
        "**Polarity prediction**: from the IMU's rotation rate and the fused velocity, the tracker predicts how each "
        "map edge moves in the image, and so whether it should produce ON or OFF events. Each point is then "
        "compared only with the time surface of its predicted polarity (red/blue, in 3D and in the live image), which removes the "
        "events and distractions of the other polarity. Points whose motion is nearly parallel to the edge sit "
        "in the *buffer zone* (yellow) and use both; so does every point when polarity prediction is off (mode `stpe`)."
    ),
    Stage.REGISTRATION: (
        "**Registration** moves the 6-DoF pose until the projected map points fall into the valleys of the TDF "
        "(robust least squares, Levenberg-Marquardt on SE(3)). Points far from any valley get small weights, so "
        "clutter does not pull the pose. The live image colours each point by its residual (green = on an edge, red = far)."
    ),
    Stage.FUSION: (
        "**Fusion** (mode `full`) combines each registration with the IMU, by default in a factor graph (gtsam; "
        "`fusion > backend` also offers an EKF): the IMU predicts the motion between registrations at its high rate "
        "(small axes in 3D), registration corrects the drift. In mode `stpe+filter` the IMU only feeds the polarity "
        "prediction and in `stpe` it is not used: the `motion model` parameter predicts the next pose (a "
        "constant-velocity Kalman filter by default). The orange line is the fused trajectory, purple the raw "
        "registrations, green the ground truth."
    ),
}

STAGE_PANEL: dict[Stage, str] = {
    Stage.EVENTS: "events kept / removed",
    Stage.SP_TS: "SP-TS positive",
    Stage.TDF: "TDF + map points",
    Stage.POLARITY: "TDF + map points",
    Stage.REGISTRATION: "TDF + map points",
    Stage.FUSION: "TDF + map points",
}
"""Which live image illustrates each stage."""

STAGE_OVERLAY: dict[Stage, OverlayColour] = {Stage.POLARITY: OverlayColour.POLARITY}
"""How the live TDF image colours the map points at a stage (residual where not listed), whatever the Images panel's
*TDF points coloured by* says: the polarity stage showed them by residual while its text spoke of red and blue, and
the registration stage's "green = on an edge" was wrong with that dropdown on weight (session 28)."""

SCENE_REFERENCES: dict[Stage, tuple[tuple[str, str], ...]] = {
    Stage.POLARITY: (("contour_map", "the contour map (points red / blue / yellow)"),),
    Stage.FUSION: (("fused", "the fused trajectory (orange)"), ("registration", "the raw registrations (purple)"),
                   ("ground_truth", "the ground truth (green)"), ("imu_poses", "the IMU-rate poses (small axes)")),
}
"""What a stage's explanation points at in the 3D view, by its *3D view* checkbox: the teaching layout hides the raw
registrations and the IMU-rate poses, so the fusion stage spoke of a purple line and small axes nobody could see;
now the text says which are hidden and where to tick them (session 28)."""


def live_facts(stage: Stage, frame: Frame | None, t0_us: int = 0) -> str:
    """One or two sentences of figures from the step on screen for ``stage`` (its time from ``t0_us``, the
    recording's start, as the time slider)."""
    if frame is None:
        return "_Press play or step to see live figures._"
    c = frame.counts
    t = f"At t = {(frame.t_us - t0_us) / 1e6:.3f} s (step {frame.index}): "
    if frame.slam is not None:
        return t + ("SLAM mode runs no map-based tracking, so this stage is not computed; SLAM's own images (tiny "
                    "frame, motion-compensated image with its tracked features) are in the images panel's SLAM tab.")
    if stage == Stage.EVENTS:
        n_in = c.get("events_in", len(frame.events_kept) + len(frame.events_removed))
        kept = c.get("events_kept", len(frame.events_kept))
        on = int(np.sum(frame.events_kept.p > 0))
        return t + f"{n_in} events arrived, {kept} kept ({on} ON, {kept - on} OFF)."
    if stage == Stage.SP_TS:
        fresh_p = int(np.sum(unit(frame.ts_positive) > 0.5))
        fresh_n = int(np.sum(unit(frame.ts_negative) > 0.5))
        return t + f"{fresh_p} pixels carry a fresh ON edge and {fresh_n} a fresh OFF edge (surface > 0.5)."
    if stage == Stage.TDF:
        return t + f"{int(np.sum(unit(frame.tdf) < 0.5))} pixels lie in an edge valley (TDF < 0.5), lowest value {float(unit(frame.tdf).min()):.2f}."
    if frame.point_index is None:
        return t + "no map is loaded, so there is nothing to register: " + (frame.reason or "tracking needs a map.")
    if stage == Stage.POLARITY:
        pol = frame.predicted_polarity if frame.predicted_polarity is not None else np.zeros(0, np.int8)
        return t + f"{int(np.sum(pol > 0))} points predicted ON, {int(np.sum(pol < 0))} OFF, {int(np.sum(pol == 0))} in the buffer zone."
    if stage == Stage.REGISTRATION:
        res = frame.residuals if frame.residuals is not None else np.zeros(0)
        med = float(np.median(res)) if len(res) else float("nan")
        return t + f"{len(res)} points used, {c.get('inliers', 0)} inliers, median residual {med:.3f}; status **{frame.status}**."
    n_imu = 0 if frame.imu_poses is None else len(frame.imu_poses)
    return t + f"{n_imu} IMU-rate poses since the last registration; status **{frame.status}**" + (f" ({frame.reason})" if frame.reason else ".")


def hidden_note(stage: Stage, toggles) -> str:
    """A line naming what the stage's text points at in the 3D view but the *3D view* checkboxes hide (empty if none)."""
    hidden = [(name, words) for name, words in SCENE_REFERENCES.get(stage, ()) if not getattr(toggles, name, True)]
    if not hidden:
        return ""
    boxes = ", ".join(f"*{name.replace('_', ' ')}*" for name, _ in hidden)
    return (f"\n\n_Hidden in the 3D view now: {' and '.join(w for _, w in hidden)}; tick {boxes} under "
            "**3D view** to show {}._".format("it" if len(hidden) == 1 else "them"))


def teaching_markdown(stage: Stage, frame: Frame | None, t0_us: int = 0, toggles=None) -> str:
    """The teaching panel's text for ``stage`` at ``frame`` (under its live image, whose caption is
    :func:`image_caption`); ``toggles`` (the 3D view's :class:`SceneToggles`) adds what the text speaks of that the
    3D view hides."""
    slam = frame is not None and frame.slam is not None
    note = hidden_note(stage, toggles) if toggles is not None and not slam else ""
    return f"### {stage.value}\n\n{EXPLANATIONS[stage]}\n\n**Now:** {live_facts(stage, frame, t0_us)}{note}"


def image_caption(stage: Stage, frame: Frame | None) -> str:
    """What the live image of ``stage`` shows, its caption ("" in SLAM mode, which shows none)."""
    if frame is not None and frame.slam is not None:
        return ""
    if stage == Stage.SP_TS:
        return "SP-TS: ON (red to yellow) and OFF (blue) surfaces in one picture"
    if STAGE_PANEL[stage] != "TDF + map points":
        return STAGE_PANEL[stage]
    if frame is not None and frame.point_index is None:
        return "TDF (no map, so no points on it)"  # the events-only view
    return f"TDF + map points, coloured by {STAGE_OVERLAY.get(stage, OverlayColour.RESIDUAL).value}"


def live_image(stage: Stage, frame: Frame, imgs: dict[str, np.ndarray], overlay: OverlayColour) -> np.ndarray:
    """The stage's live image from the panel images ``imgs`` (drawn with the Images panel's ``overlay``); the TDF is
    drawn again when the stage colours its points otherwise (:data:`STAGE_OVERLAY`), and the SP-TS stage shows both
    polarities' surfaces in one picture (its text explains both; each is black where empty)."""
    colour = STAGE_OVERLAY.get(stage, OverlayColour.RESIDUAL)
    if STAGE_PANEL[stage] == "TDF + map points" and colour != overlay:
        return tdf_image(frame, colour)
    if stage == Stage.SP_TS:
        return np.maximum(imgs["SP-TS positive"], imgs["SP-TS negative"])
    return imgs[STAGE_PANEL[stage]]


def stage_after(stage: Stage, delta: int) -> Stage:
    """The stage ``delta`` places on in the lesson's order, wrapping around (the teaching panel's previous / next)."""
    order = list(Stage)
    return order[(order.index(stage) + delta) % len(order)]
