"""Speed-proportional event leads: a pixel's threshold crossing fires a fixed time late (issue 7, session 37).

The class leads of :class:`~evpose.tracker.event_registration_config.EventRegistrationConfig` are pixels, the same
for every edge of a class. If an event fires a time ``tau`` after the edge reaches the place the lead assumes, it
trails by ``tau |v_n|`` instead (``v_n`` the edge's normal image speed). On the landing the flight moves nearby
edges (box tops) faster across the image than far ones (ground), so a lag left in constant leads reads as a
depth-dependent offset, which registration can take up as translation against tilt. This adds ``-tau (|v_n| -
v_ref)`` to each event's lead (``v_ref`` the reference speed, an angle per second, at which the leads were
measured, so the leads' mean over a flight stays), ``tau`` per polarity.

Measured (session 37, ``/tmp/s37/rt37/lag.py`` on session 32's per-event offsets from the simulator's true edges at
the true pose, ``/tmp/s32/edge32/off_*.npz``; slope of the offset on ``|v_n|`` within each true edge segment, so the
segments' own contrast offsets drop out): OFF events lag 0.21 +- 0.08 / 0.12 +- 0.08 ms (240x180 2 s seeds 1 / 2),
0.27 +- 0.05 ms (240x180 3 s seed 0), 0.16 +- 0.04 ms (346x260 2 s seed 0); ON events -0.09 +- 0.15 / +0.05 +- 0.15,
+0.73 +- 0.09, -0.12 +- 0.07 ms (no consistent sign). The flights' mean normal speed is 0.81-0.84 rad/s at both
sensors (144 px/s at 240x180, 201 px/s at 346x260). No image-axis offset: regressed on the edge normal's image
components the events sit within 0.05 px of their polarity's mean along x and y (``/tmp/s37/rt37/axis.py``), and
the per-segment mean offsets spread 0.07-0.12 px at both sensors (in pixels, so 1.44x the angle at 240x180;
``feat.py``), none of it following the edge's speed, its obliqueness to the motion, its angle to the pixel grid or
its depth by more than +-0.06 px between quintiles.

Off: it does not help (``full`` from ground truth through the CLI, ``/tmp/s37/rt37/run.sh`` and ``cmp.py``, cached
240x180 2 s landings seeds 0-23, paired against main's defaults 5.060 mm, ARE 0.0597 deg): OFF 200 us 5.092 (+0.033
+- 0.064, 10 of 24 better), ARE 0.0586; ON and OFF 200 us 5.086 (+0.026 +- 0.059, 13 of 24), ARE 0.0578; OFF 400 us
5.124 (+0.064 +- 0.099, 12 of 24), ARE 0.0587. From the truth (``oracle.py`` with ``ORACLE=1``: every prediction the
true pose; ``slow.py``: RMS of the 50-update moving mean of each registration's camera-frame error, seeds 0-3) the
events' slow error along the shift-x / tilt-about-y ridge (``(x - h ry) / 2``) goes 3.94 mm (defaults) -> 4.03 /
4.03 / 4.13 mm with these three and 3.92 / 3.90 mm with both lags at -200 / -400 us; the combined registration's
3.17 -> 3.20 / 3.22 / 3.27 and 3.18 / 3.19 mm. What a lag changes is small against the per-edge spread: the events'
mean normal speed is 176 px/s on the nearest fifth of them (2.1-3.1 m) and 109 px/s on the farthest (beyond 4.7 m;
240x180 seed 1), so 0.2 ms moves the near edges' leads against the far ones' by 0.013 px, where the segments'
means spread by 0.08-0.12 px.

Session 42 (``/tmp/s42/lag42``), the other flights' ridge (registrations from the TRUE pose biased along shift-x /
tilt-about-y, 240x180 flights 2 / 9, 0.25-1.25 s: -9.5 mm / +145 mdeg and -11.9 / +179, which removing the 1 m box
from the map mostly removes): not a lag either, nor one image shift of the box. Each registration's events
linearised at the true pose (``perpt.py``: the events' per-point robust mean residual, leads applied, ``shiftfit.py``)
and fitted per group as one common image shift or one time lag ``r = -eps v_n``: the box's rims sit +0.03 / +0.05 px
along their motion (lag -0.22 / -0.34 ms), the ground-level points -0.20 / -0.21 px (lag +1.66 / +1.70 ms), other
raised points -0.04 / -0.03: no common lag; what the ground shows is one edge, a 4 m building's foot beside the box
(true segment 16, ``bygroup.py``, ``bypol.py``), whose ON events trail it by 0.27 / 0.31 px against a -0.07 lead.
The events' Gauss-Newton step from the truth those residuals ask for (``whatif.py``, ``leadsweep.py``; x mm / ry
mdeg) is -8.3 / +120 and -17.7 / +218; with this module's lag at 0.2 / 0.5 / 1.0 ms on both polarities -8.2 / +121,
-8.1 / +122, -7.9 / +124 (flight 9 -17.8 / +220, -18.0 / +224, -18.2 / +230), -0.5 ms -8.4 / +118 (-17.5 / +212);
a lead scaled with depth (0.1 px x (Z_mean / Z - 1)) -7.2 / +107 (-16.5 / +201); that foot's points left out -2.7 /
+38 (-8.2 / +86). Leaving the foot out of the map in the oracle (``or_d16_*``) takes the ridge to -2.2 / +32 and
-0.5 / +10: the foot, not the box, is what is off, by the contrast mechanism of
:mod:`evpose.tracker.contrast_leads` (its log contrast 0.50 against the simulator's 0.40 threshold: one event per
passage, fired about three quarters through the transition).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class EventLagConfig:
    """Per-polarity event lag of :mod:`evpose.tracker.event_lag` (off by default; see the module for the figures)."""

    on_lag_us: float = field(default=0.0, metadata={"min": -2000.0, "max": 2000.0, "step": 10.0, "unit": "us"})
    """How late an ON event fires after its edge reaches the place its class lead assumes, microseconds (0 = off)."""
    off_lag_us: float = field(default=0.0, metadata={"min": -2000.0, "max": 2000.0, "step": 10.0, "unit": "us"})
    """As ``on_lag_us`` for OFF events, microseconds (0 = off)."""
    reference_mrad_s: float = field(default=830.0, metadata={"min": 0.0, "max": 10000.0, "step": 10.0, "unit": "mrad/s"})
    """Normal image speed of an edge at which the lag adds nothing (the class leads were measured about it), as an
    angle per second (times ``fx`` for pixels per second), milliradians per second: the landings' mean, 0.81-0.84
    rad/s at both sensors."""

    @property
    def enabled(self) -> bool:
        return float(self.on_lag_us) != 0.0 or float(self.off_lag_us) != 0.0


def lead_terms(burst: np.ndarray, config: EventLagConfig, fx: float) -> np.ndarray:
    """The events' kernel's ``burst`` array (size 0 or 5, see ``follower_crossings``) extended to 8 entries with the
    lags in seconds and the reference speed in pixels per second for a camera of focal length ``fx`` (pixels);
    ``burst`` itself when the lag is off."""
    if not config.enabled:
        return burst
    out = np.zeros(8)
    out[: burst.shape[0]] = burst
    out[5] = float(config.on_lag_us) * 1e-6
    out[6] = float(config.off_lag_us) * 1e-6
    out[7] = float(config.reference_mrad_s) * 1e-3 * float(fx)
    return out
