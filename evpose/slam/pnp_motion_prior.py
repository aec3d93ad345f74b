"""Event-only PnP poses held to the map's own motion: a motion-only refinement with a constant-velocity prior.

An event-only MCI pose is solved by PnP on 12-30 tracked map points in a narrow view, where a small tilt and a sideways
shift move the image almost alike (:mod:`evpose.slam.gyro_prior` says the same of the landing): each pose trades some
rotation error for translation, and the step between two MCIs (a few ms, under a centimetre) is swamped by it. Session
32 measured the PnP-placed steps indoors at 0.33 of their length off (coasted steps, which follow a held velocity,
0.14). An event-inertial map has the gyro for that; an event-only map has only its own recent motion. This refinement
adds a prior pulling each PnP pose towards the pose the map's camera-frame rotation rate and velocity over the newest
poses predict (:func:`evpose.slam.event_coasting.event_only_coast_pose`), with a translation sigma proportional to the
predicted step (the monocular scale is unknown) and a rotation sigma in degrees, under Huber reprojection errors.
Figures: :attr:`evpose.slam.tracking_config.TrackingConfig.pnp_motion_prior_ratio`.

Where the rooms' residual sits by the pose's age (session 33, ``/tmp/s33/dir33/ana6.py`` / ``ana7.py`` / ``ana5.py`` /
``zero.py``; indoor event-only seeds 0-19, each map's Sim(3), share of the squared position residual; room prior on,
defaults in brackets). Not one indoor coast was placed again by PnP (0 of 86 with the prior, 0 of 85 without): every
coast is dead reckoning that ends in a loss, and 78 (75) of them ran on zero tracked map points for three MCIs or more.
Coasted poses more than 0.4 s after the map's last PnP pose (blank walls do not use up ``coast_s``): 27 poses, 126 mm
RMS, 10.9 % (28, 161 mm, 8.3 %); 0.2-0.3 s after it 11.6 % (3.6 %); each map's first pose 17.2 % at 80 mm (6.6 % at 74
mm); PnP poses in the map's first 0.05 s 15.4 % at 50 mm. The PnP-placed 0.1 s steps that start in a map's first 0.1 s
are 0.62 (0.79) of their length off, the later ones 0.27 (0.37): the error is the young map's (two keyframes over a
short baseline), and the camera moves mostly along its own x axis (0.92 of the step), the step error sharing x and z
(0.40 / 0.39 of the length; ``ana4.py``), so both the length and the direction of travel are at fault there.
"""

from __future__ import annotations

import cv2
import numpy as np

from evpose.slam.reprojection_normal_equations import refine_with_prior


def refine_pose_with_pose_prior(K: np.ndarray, Xw: np.ndarray, uv: np.ndarray, T_cw: np.ndarray, T_cw_prior: np.ndarray,
                                sigma_rot_rad: float, sigma_trans: float, huber_px: float = 2.0,
                                iterations: int = 8) -> np.ndarray:
    """Gauss-Newton on ``T_cam_world`` minimising Huber reprojection errors (1 px sigma) plus the prior residual
    ``Log(T_cw T_cw_prior^-1)`` weighted by ``1 / sigma_rot_rad`` (rotation) and ``1 / sigma_trans`` (translation,
    map units; the translation part is the prior's camera centre seen from the estimate, so its length is the distance
    between the two centres). Perturbations act on the left (``T <- Exp(delta) T``), where the prior's Jacobian is the
    identity to first order. A sigma <= 0 leaves that part free. Returns the refined ``T_cam_world`` (4, 4)."""
    T_prior_inv = np.linalg.inv(np.asarray(T_cw_prior, np.float64))
    w_rot = 1.0 / sigma_rot_rad if sigma_rot_rad > 0 else 0.0
    w_tr = 1.0 / sigma_trans if sigma_trans > 0 else 0.0

    def add_prior(T, H, g):
        E = T @ T_prior_inv
        H[:3, :3] += np.eye(3) * w_rot**2
        g[:3] += cv2.Rodrigues(E[:3, :3])[0].ravel() * w_rot**2
        H[3:, 3:] += np.eye(3) * w_tr**2
        g[3:] += E[:3, 3] * w_tr**2

    T = refine_with_prior(K, np.asarray(Xw, np.float64), np.asarray(uv, np.float64), T_cw, add_prior, huber_px,
                          iterations=iterations)
    return T if np.all(np.isfinite(T)) else np.array(T_cw, np.float64)
