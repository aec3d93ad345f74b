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
