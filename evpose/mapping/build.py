"""``build_contour_map``: a raw point cloud in, the contour map EV-Pose tracks against out.

Stages (EV-Pose VI-B, NOTES.md "Map construction"):

1. optional voxel downsampling (deterministic averaging per voxel);
2. kNN PCA normals and curvature ``lambda0/(lambda0+lambda1+lambda2)``; for region growing,
   points with a mixed neighbourhood (a crease, a cabinet's back 5-10 cm in front of a wall)
   get a one-sided normal refitted to their own surface (:mod:`evpose.mapping.robust_normals`);
3. region growing (seeds by lowest curvature, normal-angle, curvature and plane-offset
   limits), noise fragments of one plane merged, small regions dropped, a plane per
   region, regions extended up to their edges; then a second pass over the points left
   unexplained, with neighbourhoods among those points only (furniture backs in a gap in
   front of a wall; :mod:`evpose.mapping.leftover_regions`), merged with the first pass's
   fragments of the same plane;
4. per region: project, rasterise, close, trace, resample, refine to the points,
   straighten straight runs, drop the scan's own rim; contour points next to another
   plane snapped onto the planes' intersection line (of several crease lines across the
   edge, the innermost: the sofa's back, not the wall behind it; optionally on planes refitted
   without the strips along the creases, :mod:`evpose.mapping.crease_planes`), contour points of low steps
   (no region on the step's face) moved onto the face's points (a second, wider look where
   the face is sampled sparser than the scan); regions only a point or two wide (a step's
   side) give no contour of their own;
5. per point: edge normal, plane normal, region, curvature, brightness sign;
6. with intensity or colour: brightness (albedo) edges inside each region - painted
   markers, pictures, doors (:mod:`evpose.mapping.albedo_edges`), sign +1 with the normal
   pointing dark -> bright; along the rim of a panel proud of its wall (two layers) the edge
   is placed by where the panel's points end, squared to the wall's creases and closed at its
   corners (:mod:`evpose.mapping.panel_rims`), and put at the step's mid-depth
   (:func:`evpose.mapping.visibility.mid_layer_depth`);
7. optionally (``merge_double_m`` > 0) one contour per edge instead of one per region on
   either side of it (:mod:`evpose.mapping.dedup`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from evpose.core.contour_map import ContourMap
from evpose.errors import InputError
from evpose.mapping.albedo_edges import region_albedo_edges
from evpose.mapping.adjacency import crease_axes, orient_plane_normals, snap_to_intersections, snap_to_steps
from evpose.mapping.brightness import brightness_signs
from evpose.mapping.contours import trace_region
from evpose.mapping.crease_planes import refit_crease_planes, resnap_creases
from evpose.mapping.dedup import merge_double_contours
from evpose.mapping.leftover_regions import grow_leftover_regions
from evpose.mapping.normals import estimate_neighbourhoods, voxel_downsample
from evpose.mapping.region_growing import extend_to_planes, fit_regions, grow_regions, merge_coplanar, refit_planes
from evpose.mapping.robust_normals import robust_normals
from evpose.mapping.spatial import BoxIndex
from evpose.mapping.step_fit import dominant_axis
from evpose.mapping.step_lines import fit_step_runs
from evpose.mapping.visibility import front_layer, mid_layer_depth


class MapBuildError(InputError):
    """A cloud from which no contour map can be built (empty, NaN, too few points, no contour)."""


MAX_RASTER_CELLS = 5e7
"""Most raster cells the contour cell may lay over the cloud's two largest extents. Below the field's range (0 =
automatic) any tiny cell passed, and the contour rasters then never finished: on the 30 x 30 m landing cloud (17 k
points, automatic cell 0.20 m) cell 0.02 m (2.3e6 cells) took 8 s, 0.005 m (3.6e7) 58 s, 0.002 m (2.3e8) over 200 s,
0.001 m over 600 s and 1e-9 m forever, none answering SIGTERM (numba loops; session 30, /tmp/s30/fuzz30/). A bound
on the raster, not on the cell, since the cost is the scene's area over the cell's. Not applied to the automatic cell
(1.5 x the point spacing): over a whole extent it would refuse a few dense scans far apart, whose regions' rasters
:mod:`evpose.mapping.contours` already bounds one by one; an automatic cell on one very dense, very wide surface is
still unguarded."""


def check_raster(points: np.ndarray, cell_m: float) -> None:
    """Refuse a given contour cell (``cell_m`` > 0) that would raster the cloud's extent into more than
    :data:`MAX_RASTER_CELLS` cells."""
    if cell_m <= 0 or points.shape[0] == 0:
        return
    small, large = np.sort(np.ptp(points, axis=0))[-2:]
    cells = (small / cell_m + 1.0) * (large / cell_m + 1.0)
    if cells > MAX_RASTER_CELLS:
        raise MapBuildError(None, f"cell_m {cell_m!r} m would raster the cloud's {large:.1f} x {small:.1f} m into {cells:.1e} cells"
                            f" (at most {MAX_RASTER_CELLS:.0e}): give a coarser --cell, or 0 for the automatic one")


@dataclass(frozen=True)
class MapBuildConfig:
    """Parameters of contour-map construction. Lengths in metres, angles in degrees."""

    voxel_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.2, "step": 0.005, "unit": "m"})
    """Voxel edge for downsampling before anything else, metres; 0 = keep every point."""
    k_neighbours: int = field(default=16, metadata={"min": 6, "max": 100, "step": 1, "unit": "points"})
    """Neighbours per point for PCA normals/curvature and the region-growing graph."""
    robust_normals: bool = True
    """Refit the normal of points with a mixed neighbourhood (creases, parallel layers a few cm apart) to their own surface (:mod:`evpose.mapping.robust_normals`)."""
    robust_cutoff_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.2, "step": 0.001, "unit": "m"})
    """Neighbours farther than this from a point's refitted plane get no weight, metres; 0 = plane_distance_m (what is farther is not on the plane)."""
    robust_min_curvature: float = field(default=0.01, metadata={"min": 0.0, "max": 0.33, "step": 0.001, "unit": ""})
    """Only points whose PCA curvature exceeds this are refitted (clean planar points keep their PCA normal); dimensionless."""
    angle_threshold_deg: float = field(default=15.0, metadata={"min": 1.0, "max": 45.0, "step": 0.5, "unit": "deg"})
    """Largest angle between neighbouring normals inside one region, degrees."""
    plane_angle_deg: float = field(default=25.0, metadata={"min": 1.0, "max": 90.0, "step": 0.5, "unit": "deg"})
    """Largest angle between a point's normal and its region's mean normal, degrees (keeps regions planar)."""
    merge_angle_deg: float = field(default=10.0, metadata={"min": 0.0, "max": 45.0, "step": 0.5, "unit": "deg"})
    """Neighbouring regions whose planes agree within this angle (and plane_distance_m) are merged, degrees."""
    curvature_limit: float = field(default=0.06, metadata={"min": 0.001, "max": 0.33, "step": 0.001, "unit": ""})
    """Points with larger curvature join a region but do not grow it (and never seed one); dimensionless."""
    min_region_points: int = field(default=25, metadata={"min": 3, "max": 100000, "step": 10, "unit": "points"})
    """Regions with fewer points are dropped (noise fragments of one plane are merged before). 25 keeps a 0.5 m box's faces on a 100 points/m^2 scan (measured: 40 dropped them; indoor recall +2-3 points, no precision loss)."""
    grow_offset_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.2, "step": 0.001, "unit": "m"})
    """Largest offset of a point from a growing region's running plane, metres; 0 = 2x plane_distance_m (a shelf's back 5 cm in front of the wall stays apart; measured: 3x let it join the wall)."""
    plane_distance_m: float = field(default=0.015, metadata={"min": 0.001, "max": 0.1, "step": 0.001, "unit": "m"})
    """Unassigned points within this distance of a neighbouring region's plane join that region (~3x range noise), metres."""
    leftover_regions: bool = True
    """Grow a second round of regions over the points the first left unexplained, with neighbourhoods among those points only (a furniture back 5-10 cm in front of a wall; :mod:`evpose.mapping.leftover_regions`)."""
    leftover_k: int = field(default=8, metadata={"min": 4, "max": 100, "step": 1, "unit": "points"})
    """Neighbours per point among the leftover points (the second pass); fewer than k_neighbours, as its surfaces are small (a 0.5 m box face holds ~25 points at 100 points/m^2)."""
    leftover_min_points: int = field(default=10, metadata={"min": 3, "max": 100000, "step": 1, "unit": "points"})
    """Smallest region of the second pass, points (it must also be planar within plane_distance_m and spread at least leftover_min_width). Measured on the indoor scene: 10 keeps the 0.5 m box's faces (recall +1.5 points, precision -0.5); landing unchanged."""
    leftover_min_width: float = field(default=0.75, metadata={"min": 0.0, "max": 5.0, "step": 0.05, "unit": "spacings"})
    """Smallest spread (std along its minor in-plane axis) of a second-pass region, median point spacings: the strips left along creases and rims are narrower. A whole 0.5 m box face has a std of 0.14 m, under the former 1.5 spacings (0.15 m at 100 points/m^2); measured 1.5 -> 0.75 on four indoor clouds (bundled, re-samples 1-3): the 0.5 m box's recall 0.35 -> 0.87 on one, indoor recall +0.5 points and precision +0.1 on average; landing the same on those, but on re-sample 0 two 15 cm pad sides get regions and the painted 'H' recall fell 0.76 -> 0.65."""
    extend_passes: int = field(default=4, metadata={"min": 0, "max": 20, "step": 1, "unit": "passes"})
    """kNN hops by which regions may grow onto their planes after region growing."""
    cell_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.2, "step": 0.001, "unit": "m"})
    """Raster cell for contour tracing, metres; 0 = 1.5x the median point spacing."""
    close_cells: int = field(default=2, metadata={"min": 0, "max": 10, "step": 1, "unit": "cells"})
    """Radius of the morphological closing that bridges sampling gaps, raster cells."""
    min_hole_m2: float = field(default=0.0, metadata={"min": 0.0, "max": 1.0, "step": 0.001, "unit": "m^2"})
    """Holes in a region smaller than this are filled (sampling gaps), square metres; 0 = max(0.01, (8x spacing)^2)."""
    contour_spacing_m: float = field(default=0.01, metadata={"min": 0.002, "max": 0.2, "step": 0.001, "unit": "m"})
    """Distance between consecutive contour points, metres."""
    adjacent_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "m"})
    """A boundary is an object contour only if another surface lies within this distance; otherwise it is the scan's rim, metres; 0 = max(3x spacing, 5 cm)."""
    snap: bool = True
    """Snap contour points next to a non-parallel region onto the two planes' intersection line, and points of low steps onto the step's face."""
    snap_radius_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "m"})
    """Search radius for the adjacent region whose plane intersection the contour is snapped to, metres; 0 = max(5x spacing, 4 cm). On a 100 points/m^2 scan the raster contour can lie 10+ cm from the other surface's nearest points; measured 3x -> 5x spacing: indoor precision 91.1 -> 94.9 % (six re-samplings), landing 96.2 -> 99.0 %; larger radii change nothing (the 16 nearest points bound the reach)."""
    snap_min_angle_deg: float = field(default=30.0, metadata={"min": 5.0, "max": 90.0, "step": 1.0, "unit": "deg"})
    """Only planes meeting at least at this angle define a crease to snap to, degrees."""
    snap_min_width: float = field(default=2.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "spacings"})
    """A region is a crease-snap target only if its points spread at least this many median point spacings (std) along its minor in-plane axis: a strip a couple of points wide (a 15 cm step's side) has an ill-defined tilt. Measured: 3 -> 2 lets the 40 cm sides of a shelf at 100 points/m^2 define its front's creases (indoor precision +2.6 points, landing +0.6)."""
    snap_across_cells: float = field(default=0.5, metadata={"min": 0.0, "max": 5.0, "step": 0.05, "unit": "cells"})
    """Of the crease lines a contour point could snap to by a move across its edge (sideways part under this many raster cells), the innermost is taken - the sofa's back, not the wall 10 cm behind it; measured 0.25-1 alike (indoor precision +1.1 points)."""
    snap_max_shift_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "m"})
    """Largest move of a contour point onto a crease line, metres; 0 = the snap radius."""
    step_min_points: int = field(default=1, metadata={"min": 1, "max": 32, "step": 1, "unit": "points"})
    """Fewest points of a low step's face that move a contour point onto it (:func:`evpose.mapping.adjacency.snap_to_steps`), points. The landing pad's 15 cm sides are sampled sparser than the scan's median (one or two points within 2 cells): with 3 its rim stayed on the top's last points, 3-10 cm inside the true rim, and the ground's contour as far outside its foot. Measured 3 -> 1 with step_retry_radius_cells 4 (2 s landing, seeds 0-3): pad points misplaced by > 2 cm 411 / 739 / 997 / 686 -> 108 / 139 / 496 / 300; bundled landing precision / recall 99.01 / 96.47 -> 99.34 / 96.82 %; indoor (bundled) 97.97 / 92.31 -> 97.91 / 92.37 %."""
    step_retry_radius_cells: float = field(default=4.0, metadata={"min": 2.0, "max": 10.0, "step": 0.5, "unit": "cells"})
    """Search radius, raster cells, of a second look for a low step's face points around contour points the first (2 cells) left unmoved; 2 = no second look. A single look at 4 cells moved indoor points onto wrong faces (bundled indoor precision 97.97 -> 97.33 %); the second look only where the first found nothing keeps the landing gain (see step_min_points) at indoor 97.91 %."""
    step_retry_shift_cells: float = field(default=1.5, metadata={"min": 0.5, "max": 10.0, "step": 0.5, "unit": "cells"})
    """Largest move onto a step's face in the second look (step_retry_radius_cells), raster cells (the first look's limit is 1.5). Measured 1.5 -> 2.5 (2 s landing, seeds 0-3): pad points misplaced 108 / 139 / 116 / 92 -> 43 / 139 / 147 / 43, bundled landing precision / recall 99.33 / 96.82 -> 99.40 / 96.88 %, but indoor 97.91 / 92.37 -> 97.83 / 92.22 % and tracking no better: ablation_seeds stpe ATE 15.8 / 23.8 -> 16.0 / 23.9 mm, full 9.06 / 9.50 -> 9.09 / 9.73 mm (346x260 / 240x180); so 1.5."""
    step_lines: bool = False
    """Replace each straight run of a low step's edge (not on a crease) by the line fitted to all of its face's points along the run (:mod:`evpose.mapping.step_lines`), instead of each point's median of its few nearest face points. Off by default: the map is better, tracking only within its noise. Measured (session 30, details in the module): the pad's and crates' rims near the pad 2.9 / 3.9 -> 2.1 / 3.0 mm RMS (feet / tops), landing and indoor precision and recall up 0.05-0.4 points; ``full`` (2 s landing from ground truth) seeds 0-11 346x260 4.621 -> 4.471 mm, 240x180 5.438 -> 5.313, but held-out seeds 12-23 5.551 -> 5.653 and 6.445 -> 6.490 (0-23: -0.02 / -0.04 mm, 11 of 24 seeds better at each); demos landing / landing_fast / landing_dynamic 7.12 / 9.98 / 5.90 -> 7.24 / 9.53 / 4.97 mm. On, the bundled ``maps/landing_map.ply`` must be rebuilt (``tests/test_blas_kernels.py`` checks it is what ``evpose build-map maps/landing_cloud.ply`` writes). Session 39 (main
    5eab5e0, ``full``, 240x180 2 s landing from ground truth, each seed's map rebuilt with it from its own cloud, paired
    against the default map; ``/tmp/s39/tr39`` ``vrun.sh``, ``cmp.py``): seeds 0-23 4.934 -> 4.948 mm (+0.01 +- 0.11, 11 of
    24 better), held-out seeds 24-47 (12 run) +0.08 +- 0.11 (4 of 12): still neutral, though it takes the top rims in view
    (pad, crates, buildings) from 3.58 to 2.30 mm RMS and the feet from 3.54 to 2.87 (seeds 0-7, ``buildvar.py``)."""
    crease_refit: bool = True
    """Snap crease points onto the intersection of planes refitted away from the creases (points within crease_band_m of a crease partner's plane left out, outliers trimmed at 2.5 robust sigmas; :mod:`evpose.mapping.crease_planes`) instead of the regions' plain least-squares planes. On by default since session 31 (with crease_square_deg 3, crease_refit_feet off): the map is better, tracking better at 346x260 and level at 240x180 over seeds 0-23 (figures below). Measured (session 30, ``/tmp/s30/rim30/``; crates' and buildings' top rims within 4 m of the pad, seeds 0-3, with crease_square_deg 3): 2.10 -> 1.40 mm RMS, bias -0.55 -> 0.00 mm, > 2 mm off 17.5 -> 2.8 %. ``full`` (2 s landing from ground truth, seeds 0-11, mean ATE, paired against the plain builder in the same checkout, 4.625 / 5.453 mm at 346x260 / 240x180): crease_square_deg 3 346x260 4.434 mm (-0.19 +- 0.23, 7 of 12 better), 240x180 5.784 (+0.33 +- 0.25, 5 of 12; ARE 0.063 -> 0.072 deg); with crease_refit_feet off 4.306 (-0.32 +- 0.26, 8 of 12) and 5.651 (+0.20 +- 0.24, 6 of 12); crease_square_sigmas 3 at 240x180 5.822; with step_lines too (feet off) 4.301 (-0.32 +- 0.23, 8 of 12) and 5.703 (+0.25 +- 0.27, 4 of 12). Held-out seeds 12-23 (feet off): 346x260 5.551 -> 4.858 mm (-0.69 +- 0.57, 8 of 12; seeds 21 / 22 10.52 / 8.68 -> 4.76 / 5.66), 240x180 240x180 6.445 -> 6.202 (-0.24 +- 0.47, 7 of 12; seed 21 10.15 -> 5.77); over seeds 0-23 346x260 5.088 -> 4.582 mm (-0.51 +- 0.31, 16 of 24 better), 240x180 5.949 -> 5.927 (-0.02 +- 0.26, 13 of 24). At 240x180 every variant raised the ARE of seeds 0-11 (0.063 -> 0.070-0.073 deg). Against the oracle (these top rims on the truth: 3.817 mm at 346x260) the remaining top-rim error is not what limits 240x180. Session 31 (``/tmp/s31/rim31/``: ``run.py`` / ``run2.py`` (per-update logs, the events' copy of the map swappable), ``ana.py`` / ``ana2.py`` per-axis errors, ``q1.sh``-``q5.sh``; this checkout's plain builder reproduces session 30's figures bit for bit), why it became the default, paired over seeds 0-23 against the plain builder (mean ATE mm, +- paired standard error, seeds better; ARE deg): 346x260 5.088 -> 4.582 (-0.51 +- 0.31, 16 of 24), ARE 0.0678 -> 0.0560 (-0.012 +- 0.006); 240x180 5.949 -> 5.927 (-0.02 +- 0.26, 13 of 24), ARE 0.0768 -> 0.0732 (-0.004 +- 0.006): the ARE rise session 30 saw is seeds 0-11 only (+0.007 +- 0.007), seeds 12-23 fell 0.0905 -> 0.0767. crease_square_sigmas 3 (feet off) is not safer for tracking: seeds 0-11 346x260 4.395 mm, 240x180 5.758, equal to sigmas 0 on 8 of 12 seeds and worse on the other four at both (seeds 2 / 3 / 7: +0.38 / +0.06 / +0.64 and +1.02 / +0.12 / +0.14 mm), so it stays 0. Bundled demos (``evpose track demo_data/X.h5 --map`` the bundled cloud rebuilt, ``evpose eval --align none``, ATE RMSE / ARE): ``landing`` 7.12 -> 6.57 mm / 0.062 -> 0.053 deg, ``landing_fast`` 9.98 -> 10.11 / 0.090 -> 0.099, ``landing_dynamic`` 5.90 -> 5.91 / 0.063 -> 0.054. Contour precision / recall (2 cm; ``prscore.py`` = :mod:`evpose.bench.mapping`'s score, sample_cloud seeds 0-1 and the bundled clouds): landing mean of 3 99.41 / 96.74 -> 99.41 / 96.75 % (p95 distance 2.4-2.7 -> 1.9 mm), indoor 97.16 / 90.55 -> 97.16 / 90.43 % (indoor0 / 1 recall 88.83 / 90.44 -> 88.63 / 90.29, bundled 92.37 -> 92.36). Where the 240x180 figure comes from (every fused pose of seeds 0-23, camera frame at the truth; the flight moves along the camera's +x at 3 m/s): the rotation about x and the sideways (y) error drop (fused RMS -14.9 +- 5.6 mdeg, -0.54 +- 0.32 mm) and the rotation about y with the shift along the motion (x) grow (+12.0 +- 3.6 mdeg, +0.70 +- 0.21 mm): the along-motion bias, +1.70 mm / -24.5 mdeg about y in every seed alike, becomes +2.76 mm / -40.0 mdeg. It is the events' registration (:mod:`evpose.tracker.event_registration`) reading the new map that does it: the field reading the new map and the events the plain one 5.824 mm (-0.13 +- 0.07, ARE -0.003 +- 0.001: every axis a little better), the events reading the new map and the field the plain one 6.038 (+0.09 +- 0.24, the same trade and the same per-seed pattern as the new map for both). The events add +2.0 mm along the motion to the field's pose with either map (their OFF leads, tuned on the plain map, place it ahead); halving the three OFF leads (``off_lead_px`` / ``crease_off_lead_px`` / ``grazing_off_lead_px`` -0.055 / -0.11 / -0.14) on the new map removes that bias (+2.76 -> +0.02 mm, ARE 0.0732 -> 0.0639) but the height and sideways errors grow (+0.91 / +0.89 mm RMS): 6.352 mm (+0.43 +- 0.22 against the new map with the leads as set), so the leads' size trades the along-motion bias against height and is left as it is. At 346x260 the same split (``run2.py``'s ``EVMAP``): the field on the new map alone 4.875 mm (-0.21 +- 0.07, 19 of 24 better, ARE -0.004 +- 0.001), the events on it alone 4.656 (-0.43 +- 0.26), both 4.582; fused RMS change with the new map: rotation about x -17.1 +- 5.4 mdeg, sideways (y) -0.87 +- 0.28 mm, rotation about y +2.6 +- 3.4, along the motion +0.18 +- 0.23 (the along-motion bias +1.15 -> +2.39 mm): the same shift of the bias costs the finer sensor little. So the field gains at both resolutions (-0.21 / -0.13 mm, each about 3 paired standard errors) and the events' share is a trade that pays at 346x260 only; a map the events read as built by the plain planes would keep 240x180's -0.13 but is two maps, not tried. ``evpose track demo_data/landing.h5 --map maps/landing_map.ply`` now hashes ``a7cd2061617be315`` (``1c3f8d90bee2efe8`` before); the bundled maps were rebuilt with ``evpose build-map maps/<scene>_cloud.ply --out maps/<scene>_map.ply``. The events' crease OFF lead scaled to the pixel's angle lets 240x180's 2 s landings gain on this map (seeds 0-47 -0.21 +- 0.05 mm) but costs its 3 s landings +1.10 mm, so it is off: :attr:`evpose.tracker.event_registration_config.EventRegistrationConfig.crease_off_lead_pixel_exponent`."""
    crease_band_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.2, "step": 0.001, "unit": "m"})
    """With crease_refit: a region's points closer than this to the plane of a region it meets at a crease stay out of its crease plane, metres; 0 = 2x plane_distance_m."""
    crease_square_deg: float = field(default=3.0, metadata={"min": 0.0, "max": 10.0, "step": 0.5, "unit": "deg"})
    """With crease_refit: a crease plane whose normal is within this angle of the largest region's (the ground, a floor) is made parallel to it, one within it of square to it exactly square, degrees; 0 = free tilt. 3 since session 31 (session 30: without it the crates' top rims near the pad 2.01 mm RMS, with it 1.40; see crease_refit)."""
    crease_square_sigmas: float = field(default=0.0, metadata={"min": 0.0, "max": 10.0, "step": 0.5, "unit": "sigmas"})
    """With crease_square_deg: a crease plane is squared only if its deviation is also within this many standard errors of its fitted tilt (residual RMS / (sqrt(N) x the points' spread along the tilt)), so a face the scan resolves as tilted keeps its tilt; 0 = no such test."""
    crease_refit_feet: bool = False
    """With crease_refit: also the creases with the largest region (the ground, a floor: the feet) are resnapped; False (the default since session 31) = only the others (top rims, vertical edges). Session 30, seeds 0-11: on 4.434 / 5.784 mm, off 4.306 / 5.651 (346x260 / 240x180; see crease_refit). Session 39 (main 5eab5e0, ``full``, 240x180 2 s landing from ground truth, each seed's map rebuilt from its own cloud, paired against the default map; ``/tmp/s39/tr39`` ``vrun.sh``, ``cmp.py``): the seen feet's per-edge mean offset falls 1.74 -> 1.37 mm RMS and the vertical edges' 3.05 -> 2.33 (seeds 0-7, ``buildvar.py``), but tracking does not follow: seeds 0-22 4.881 -> 4.909 mm (+0.03 +- 0.06, 10 of 23 better), 33-47 +0.12 +- 0.12 (6 of 15); still off."""
    contour_min_width: float = field(default=1.5, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "spacings"})
    """Regions narrower than this (std along the minor in-plane axis, median point spacings) give no contour of their own: a strip a point or two wide (a 15 cm step's side on a sparse scan) has an ill-defined tilt, so its outline lies off both of the step's edges, which its neighbours' contours already give; 0 = every region. Measured 0 -> 1.5 (2 s landing, with the step options above): seeds 2 / 3's tilted strip across the pad's side (1.44 spacings wide) gone, pad points misplaced 496 / 300 -> 116 / 92 (seeds 0 / 1 unchanged); bundled landing precision 99.34 -> 99.33 %, bundled indoor unchanged; six indoor re-samples recall -0.05 points."""
    brightness_radius_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.5, "step": 0.01, "unit": "m"})
    """Neighbourhood compared on either side of the edge for the brightness sign, metres; 0 = max(4x spacing, 8 cm)."""
    brightness_threshold: float = field(default=0.05, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": ""})
    """Smallest median-intensity difference (intensity range scaled to [0, 1]) for a non-zero sign."""
    albedo_edges: bool = True
    """Trace brightness (albedo) edges inside each region when the cloud has intensity or colour (painted markers, pictures, doors)."""
    albedo_sigma_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "m"})
    """Smoothing scale of the in-plane intensity image, metres; 0 = 2x the median point spacing."""
    albedo_high: float = field(default=0.08, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": ""})
    """Hysteresis high threshold: intensity step (intensity in [0, 1]; other units scaled to it) that starts an edge, and the step a kept edge must reach."""
    albedo_low: float = field(default=0.04, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": ""})
    """Hysteresis low threshold: intensity step (intensity in [0, 1]) down to which an edge is followed."""
    albedo_layer_m: float = field(default=0.012, metadata={"min": 0.0, "max": 0.1, "step": 0.001, "unit": "m"})
    """A point this far behind the front layer of its region's neighbours is hidden (a wall behind a picture) and its intensity ignored, metres (~2x range noise)."""
    albedo_axis_snap_deg: float = field(default=0.0, metadata={"min": 0.0, "max": 45.0, "step": 0.5, "unit": "deg"})
    """A straight brightness edge within this angle of square to its region's outline (the dominant direction of the region's contour, when it has one) is fitted exactly square to it, degrees; 0 = free tilt. Measured 0 -> 12 on four indoor clouds (bundled, re-samples 1-3): the wall panels' (picture, door, screen) tilted edges straightened, indoor recall +1.6 points, precision +0.4 on average (re-samples 4/5: recall +2.9/-0.7); landing +0.1 precision, +0.1 recall; painted 'H' recall +2.4 to +9 points on three of four landing clouds, -2 on the bundled one. Off by default: on the 2 s landing benchmark (seed 0) the squared 'H' cost tracking, stpe 33.0 -> 38.9 mm / 0.52 -> 0.67 deg at 346x260 (42.3 -> 48.2 mm at 240x180), full ARE 0.24 -> 0.28 deg (0.31 -> 0.36), full ATE the same. (Measured with the traced outline's direction; a region with creases now takes theirs, :func:`evpose.mapping.adjacency.crease_axes`.) Session 30 (with step_lines, ``/tmp/s30/map30/``), still off: 12 deg takes the painted points' error along their normals from 11.9 to 10.8 mm RMS and those > 3 cm off from 14 to 10 % (seeds 0-3; 20 / 30 deg 10.8 / 10.6 mm), but ``full`` (2 s landing, seeds 0-11) 4.471 -> 4.595 mm at 346x260 and 5.313 -> 5.626 mm at 240x180."""
    albedo_panel_rims: bool = True
    """Place a brightness edge along the rim of a layer proud of its region (a door, picture or screen 2 cm in front of its wall, the wall sampled behind it) by where the panel's own points end, not by the intensity step fit, which the panel's side faces and the wall behind it push 1-2 cm outward (:mod:`evpose.mapping.panel_rims`); the pieces of one rim are placed together. Measured on seven indoor clouds (bundled, re-samples 1-6), with albedo_panel_snap_deg 12 and albedo_panel_gap_m 0.3: recall 85.9 -> 90.2 %, recall_faces 88.2 -> 91.3 %, precision 95.3 -> 96.1 % (picture / door / screen recall 49 / 75 / 59 -> 67 / 86 / 82 %); landing maps bit-identical (no two-layer rims there, so tracking is unchanged)."""
    albedo_panel_snap_deg: float = field(default=12.0, metadata={"min": 0.0, "max": 45.0, "step": 0.5, "unit": "deg"})
    """As albedo_axis_snap_deg, but only for straight brightness edges along the rim of a proud panel (albedo_panel_rims), degrees; 0 = free tilt. A door or picture is square to its wall, while the landing's painted 'H' (one layer) keeps its free tilt, which tracks better there. Measured 0 -> 12 on seven indoor clouds (with albedo_panel_gap_m 0.3): recall 87.0 -> 90.2 %, recall_faces 89.0 -> 91.3 %, precision 95.5 -> 96.1 %; landing unchanged. The outline direction is the region's crease lines' (:func:`evpose.mapping.adjacency.crease_axes`): the traced outline's own direction is up to 1.3 deg off on the walls (1.4 cm along a 2 m door), with it four-cloud indoor recall was 2.2 points lower."""
    albedo_panel_gap_m: float = field(default=0.3, metadata={"min": 0.0, "max": 2.0, "step": 0.01, "unit": "m"})
    """A placed panel rim (albedo_panel_rims) that stops at most this short of a square rim's line is continued to their corner where the panel's points still border it (Canny loses stretches near a panel's corners), metres; 0 = off. Measured 0 -> 0.3 on seven indoor clouds: recall 89.9 -> 90.2 %, recall_faces 91.1 -> 91.3 %, precision 96.2 -> 96.1 % (0.2 and 0.4 alike); landing unchanged."""
    albedo_corner_reach_m: float = field(default=0.0, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "m"})
    """Where two straight brightness edges of one traced chain meet at a corner, continue both fitted lines to their crossing if it lies within this distance of each, dropping the rounded curve Canny traced between them (:mod:`evpose.mapping.albedo_corners`), metres; 0 = off. Off: see albedo_marker_snap_deg (measured together; alone on indoor re-samples 1 / 2: recall 90.29 / 90.13 -> 90.66 / 90.34 %)."""
    albedo_marker_snap_deg: float = field(default=0.0, metadata={"min": 0.0, "max": 45.0, "step": 0.5, "unit": "deg"})
    """Fit a region's straight brightness edges freely first, take their common direction up to quarter turns (length-weighted) as the region's marker axis (:mod:`evpose.mapping.marker_axis`), then fit the edges within this angle of square to it exactly square, degrees; 0 = off (albedo_axis_snap_deg's outline direction applies; a proud panel's rim keeps its crease axis either way). Off by default: the map is better, tracking not. Session 41 (hm41, ``/tmp/s41/hm41``, README.txt there), 12 with albedo_corner_reach_m 0.3: the painted 'H' of the 240x180 2 s landing maps (seeds 0-23 against the simulator's ``r_edges.npz``, ``mapsum.py``): error across the edge 18.2 -> 15.6 mm RMS, the scatter along its vertical edges 14.2 -> 9.8 mm sd, recall (2 cm) 0.52 -> 0.63, but each vertical edge's mean offset stays 9.9 -> 9.5 mm RMS (noise, not a bias: its sign changes from edge to edge and seed to seed; the scan pins a 0.76 m edge only to its nearest points, ~13 mm on either side at 100 points/m^2); mapping (``mapbench.py``, bundled clouds + simulator re-samples 1-3) landing precision / recall 99.26 / 96.70 -> 99.35 / 96.91 %, painted 'H' recall 64.4 -> 76.3 %, indoor 96.90 / 90.97 -> 97.12 / 92.11 % (bundled indoor precision 97.91 -> 97.76). Tracking (``full`` from ground truth, each seed's map rebuilt from its own cloud, paired against main's maps; ``cand_chain.sh``, ``cmp.py``): 240x180 seeds 0-23 4.770 -> 4.825 mm (+0.055 +- 0.074, 11 of 24 better), held-out 24-34 5.554 -> 5.418 (-0.135 +- 0.083, 8 of 11), with step_lines too 0-23 4.766 (-0.004 +- 0.121); 346x260 and 3 s not measured; demos on ``maps/landing_cloud.ply`` rebuilt with it (``demo.sh``) landing / landing_fast / landing_dynamic 6.554 / 9.035 / 6.011 -> 6.579 / 9.053 / 6.300 mm. The true 'H' itself (an oracle: every painted point replaced by the true edges, ``oracle_map.py``) gives only 4.770 -> 4.665 (-0.105 +- 0.106, 12 of 24)."""
    albedo_mid_depth: bool = True
    """Put a brightness edge with two layers across it (a panel proud of a wall, its wall sampled behind it) at the step's mid-depth instead of in the region's plane."""
    albedo_mid_radius: float = field(default=5.0, metadata={"min": 1.0, "max": 20.0, "step": 0.5, "unit": "spacings"})
    """Neighbourhood radius in which both layers are looked for when placing a brightness edge at mid-depth, median point spacings. Measured on six indoor re-samplings: 3 -> 5 found two layers at more panel rims (recall +1.3 points on every sample, precision -0.1)."""
    albedo_min_length_m: float = field(default=0.0, metadata={"min": 0.0, "max": 2.0, "step": 0.01, "unit": "m"})
    """Shortest brightness edge kept, metres; 0 = max(0.15 m, 5x the median point spacing)."""
    merge_double_m: float = field(default=0.0, metadata={"min": 0.0, "max": 0.1, "step": 0.001, "unit": "m"})
    """Contour points of different regions closer than this are one edge seen from both sides: keep the better-supported one, metres; 0 = keep both (default: measured, merging at 2 cm made the landing tracker's ATE worse, 17.8 -> 19.6 mm)."""
    viewpoint: tuple[float, float, float] | None = None
    """Where the scan was seen from (world, metres); plane normals face it. None = z-up heuristics."""


@dataclass(frozen=True)
class _Scales:
    """Lengths actually used, after resolving the config's 'auto' (0) fields from the point spacing."""

    cell: float
    min_hole: float
    adjacent: float
    snap_radius: float
    snap_shift: float
    brightness_radius: float
    albedo_sigma: float
    albedo_min_length: float


def _scales(cfg: MapBuildConfig, spacing: float) -> _Scales:
    cell = cfg.cell_m if cfg.cell_m > 0 else max(1.5 * spacing, 1e-3)
    snap_r = cfg.snap_radius_m if cfg.snap_radius_m > 0 else max(5.0 * spacing, 0.04)
    return _Scales(
        cell=cell,
        min_hole=cfg.min_hole_m2 if cfg.min_hole_m2 > 0 else max(0.01, (8.0 * spacing) ** 2),
        adjacent=cfg.adjacent_m if cfg.adjacent_m > 0 else max(3.0 * spacing, 0.05),
        snap_radius=snap_r,
        snap_shift=cfg.snap_max_shift_m if cfg.snap_max_shift_m > 0 else snap_r,
        brightness_radius=cfg.brightness_radius_m if cfg.brightness_radius_m > 0 else max(4.0 * spacing, 0.08),
        albedo_sigma=cfg.albedo_sigma_m if cfg.albedo_sigma_m > 0 else max(2.0 * spacing, 1e-3),
        albedo_min_length=cfg.albedo_min_length_m if cfg.albedo_min_length_m > 0 else max(0.15, 5.0 * spacing),
    )


def _progress(enabled: bool, total: int, desc: str):
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="step", leave=False)


def build_contour_map(
    points: np.ndarray,
    normals: np.ndarray | None = None,
    intensity: np.ndarray | None = None,
    config: MapBuildConfig = MapBuildConfig(),
    progress: bool = False,
) -> ContourMap:
    """Contour map of a raw cloud: ``points`` (N, 3) m, optional ``normals`` (N, 3) and ``intensity`` (N,) or RGB (N, 3).

    Deterministic: the same input and config give a bit-identical map.
    Raises :class:`MapBuildError` for empty/non-finite clouds and clouds without any object contour.
    """
    from evpose.mapping.brightness import intensity_from_colors

    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise MapBuildError(None, f"points must have shape (N, 3), got {pts.shape}")
    if pts.shape[0] == 0:
        raise MapBuildError(None, "point cloud is empty")
    bad = np.flatnonzero(~np.isfinite(pts).all(axis=1))
    if bad.size:
        raise MapBuildError(None, "NaN or infinite coordinate", f"point {int(bad[0])}")
    inten = None if intensity is None else intensity_from_colors(intensity)
    if inten is not None and inten.shape[0] != pts.shape[0]:
        raise MapBuildError(None, f"intensity has {inten.shape[0]} values for {pts.shape[0]} points")
    if inten is not None and not np.isfinite(inten).all():
        raise MapBuildError(None, "NaN or infinite intensity", f"point {int(np.flatnonzero(~np.isfinite(inten))[0])}")
    nrm_in = None if normals is None else np.asarray(normals, dtype=np.float64)
    if nrm_in is not None and nrm_in.shape != pts.shape:
        raise MapBuildError(None, f"normals have shape {nrm_in.shape}, points {pts.shape}")
    if nrm_in is not None and not np.isfinite(nrm_in).all():
        nrm_in = None  # unusable normals only cost the orientation hint

    cfg = config
    bar = _progress(progress, 6, "build-map")

    def stage(name):
        if bar is not None:
            bar.set_description(f"build-map: {name}")
            bar.update(1)

    check_raster(pts, cfg.cell_m)  # before any work: a given cell is known now
    pts, inten, nrm_in = voxel_downsample(pts, cfg.voxel_m, inten, nrm_in)
    if pts.shape[0] < max(cfg.k_neighbours, 10):
        raise MapBuildError(None, f"only {pts.shape[0]} points; at least {max(cfg.k_neighbours, 10)} are needed")
    stage("normals")
    nb = estimate_neighbourhoods(pts, cfg.k_neighbours)
    # Region growing uses the one-sided normals; the map's per-point curvature stays the plain
    # PCA surface variation (EV-Pose's definition, which the tracker reads).
    grow_normals, grow_curvature = nb.normals, nb.curvature
    if cfg.robust_normals:
        grow_normals, grow_curvature = robust_normals(pts, nb.indices, nb.normals, nb.curvature,
                                                      cfg.robust_min_curvature,
                                                      cfg.robust_cutoff_m if cfg.robust_cutoff_m > 0 else cfg.plane_distance_m)

    stage("regions")
    cos_t = math.cos(math.radians(cfg.angle_threshold_deg))
    grow_offset = cfg.grow_offset_m if cfg.grow_offset_m > 0 else 2.0 * cfg.plane_distance_m
    labels = grow_regions(pts, grow_normals, grow_curvature, nb.indices, cos_t, cfg.curvature_limit,
                          math.cos(math.radians(cfg.plane_angle_deg)), grow_offset)
    # Merge before dropping small regions: noise splits a plane into fragments that are small
    # one by one.
    labels, regions = fit_regions(pts, labels, 3)
    labels = merge_coplanar(pts, nb.indices, labels, regions, math.cos(math.radians(cfg.merge_angle_deg)),
                            cfg.plane_distance_m)
    labels, regions = fit_regions(pts, labels, cfg.min_region_points)
    if regions.sizes.size == 0:
        raise MapBuildError(None, "no smooth surface found (no region reaches min_region_points)")
    labels = extend_to_planes(pts, nb.indices, labels, regions, cfg.plane_distance_m, cfg.extend_passes)
    n_regions = regions.sizes.size
    if cfg.leftover_regions:
        labels = grow_leftover_regions(
            pts, labels, regions, nb.indices, cfg.leftover_k, cos_t, cfg.curvature_limit,
            math.cos(math.radians(cfg.plane_angle_deg)), grow_offset, math.cos(math.radians(cfg.merge_angle_deg)),
            cfg.plane_distance_m, cfg.leftover_min_points, cfg.leftover_min_width * nb.spacing, cfg.robust_min_curvature,
        )
        if int(labels.max()) + 1 > n_regions:
            # A new region may be the rest of a first-pass fragment of the same plane: merge them.
            labels = merge_coplanar(pts, nb.indices, labels, refit_planes(pts, labels, int(labels.max()) + 1),
                                    math.cos(math.radians(cfg.merge_angle_deg)), cfg.plane_distance_m)
            labels, regions = fit_regions(pts, labels, min(cfg.min_region_points, cfg.leftover_min_points))
            n_regions = regions.sizes.size
            labels = extend_to_planes(pts, nb.indices, labels, regions, cfg.plane_distance_m, cfg.extend_passes)
    regions = refit_planes(pts, labels, n_regions)

    stage("contours")
    sc = _scales(cfg, nb.spacing)
    cell = sc.cell
    order = np.argsort(labels, kind="stable")
    starts = np.searchsorted(labels[order], np.arange(regions.sizes.size + 1))
    bounds = np.stack([[pts[order[starts[r]:starts[r + 1]]].min(axis=0), pts[order[starts[r]:starts[r + 1]]].max(axis=0)]
                       for r in range(regions.sizes.size)])
    plane_n = orient_plane_normals(
        regions.normals, regions.centroids, pts, labels, nrm_in,
        None if cfg.viewpoint is None else np.asarray(cfg.viewpoint, np.float64), reach=0.5, bounds=bounds,
    )
    index = BoxIndex(pts)
    far = 10.0 * sc.adjacent
    pts3, en3, reg3 = [], [], []
    axis_angles = np.full(regions.sizes.size, np.nan)
    region_bar = _progress(progress, regions.sizes.size, "contours")
    for r in range(regions.sizes.size):
        if regions.minor_std[r] < cfg.contour_min_width * nb.spacing:
            if region_bar is not None:
                region_bar.update(1)
            continue
        own = pts[order[starts[r]:starts[r + 1]]]
        c, n, ax = regions.centroids[r], regions.normals[r], regions.axes[r]
        box = index.query(bounds[r, 0] - far, bounds[r, 1] + far)
        box = box[labels[box] != r]
        off = (pts[box] - c) @ n
        # Unassigned points on this very plane are its own stragglers, not another surface.
        # (Noise puts a few of them further off than plane_distance_m: allow 5 sigma of the fit.)
        straggler_m = max(cfg.plane_distance_m, 5.0 * regions.rms[r])
        other = ~((labels[box] == -1) & (np.abs(off) < straggler_m))
        rel = pts[box] - c
        o2 = np.stack([rel @ ax[0], rel @ ax[1]], axis=1)
        adjacent2d = o2[other & (np.abs(off) <= sc.adjacent)]
        near2d = o2[other & (np.abs(off) <= far)]
        own_rel = own - c
        own2d = np.stack([own_rel @ ax[0], own_rel @ ax[1]], axis=1)
        rc = trace_region(own2d, adjacent2d, near2d, cell, cfg.close_cells, sc.min_hole,
                          cfg.contour_spacing_m, sc.adjacent)
        p2, e2 = rc.points2d[rc.keep], rc.normals2d[rc.keep]
        # All of the traced outline, the scan's rim too: a wall's rim runs along the room's corners.
        axis = dominant_axis(rc.normals2d)
        if axis is not None:
            axis_angles[r] = axis
        pts3.append(c + p2[:, :1] * ax[0] + p2[:, 1:] * ax[1])
        en3.append(e2[:, :1] * ax[0] + e2[:, 1:] * ax[1])
        reg3.append(np.full(p2.shape[0], r, np.int32))
        if region_bar is not None:
            region_bar.update(1)
    if region_bar is not None:
        region_bar.close()
    if not pts3:  # every region too narrow for a contour of its own
        pts3, en3, reg3 = [np.zeros((0, 3))], [np.zeros((0, 3))], [np.zeros(0, np.int32)]
    cpts = np.concatenate(pts3)
    cen = np.concatenate(en3)
    creg = np.concatenate(reg3)

    stage("creases")
    crease = np.full(cpts.shape[0], -1, np.int32)
    if cfg.snap:
        cen_unit = cen / np.maximum(np.linalg.norm(cen, axis=1, keepdims=True), 1e-12)
        traced = cpts
        cpts, crease = snap_to_intersections(
            cpts, creg, labels, nb.tree, regions.centroids, regions.normals,
            sc.snap_radius, math.radians(cfg.snap_min_angle_deg), sc.snap_shift,
            reliable=(regions.minor_std >= cfg.snap_min_width * nb.spacing) & (regions.rms <= cfg.plane_distance_m),
            outward=cen_unit, across_tol=cfg.snap_across_cells * cell,
        )
        if cfg.crease_refit:
            # The plain fits hold the neighbours' points along the creases: refit them without.
            pairs = np.unique(np.stack([creg[crease >= 0], crease[crease >= 0]], axis=1), axis=0)
            band = cfg.crease_band_m if cfg.crease_band_m > 0 else 2.0 * cfg.plane_distance_m
            cc, cn = refit_crease_planes(pts, labels, pairs, regions.centroids, regions.normals, band,
                                         square_deg=cfg.crease_square_deg, square_sigmas=cfg.crease_square_sigmas)
            resnap = crease if cfg.crease_refit_feet else np.where((creg == 0) | (crease == 0), -1, crease)
            cpts = resnap_creases(traced, cpts, creg, resnap, cc, cn, sc.snap_shift)
        stepped = snap_to_steps(
            cpts, cen_unit, creg, crease < 0, pts, labels, nb.tree, regions.normals,
            radius=2.0 * cell, min_offset=cfg.plane_distance_m, max_offset=sc.adjacent, max_shift=1.5 * cell,
            min_count=cfg.step_min_points,
        )
        if cfg.step_retry_radius_cells > 2.0:
            # Where the scan is sparser than its median spacing (the landing pad's sides), too few of
            # the face's points lie within 2 cells: look again, farther, for the points left unmoved.
            unmoved = (crease < 0) & np.all(stepped == cpts, axis=1)
            stepped = snap_to_steps(
                stepped, cen_unit, creg, unmoved, pts, labels, nb.tree, regions.normals,
                radius=cfg.step_retry_radius_cells * cell, min_offset=cfg.plane_distance_m, max_offset=sc.adjacent,
                max_shift=cfg.step_retry_shift_cells * cell, min_count=cfg.step_min_points,
            )
        cpts = stepped
        if cfg.step_lines:
            # One line per straight run of a low step's edge, from all of its face's points.
            parallel = math.cos(math.radians(cfg.snap_min_angle_deg))
            cpts, cen_unit, _ = fit_step_runs(
                cpts, cen_unit, creg, crease < 0, pts, labels, nb.tree, regions.centroids, regions.normals,
                radius=cfg.step_retry_radius_cells * cell, min_offset=cfg.plane_distance_m, max_offset=sc.adjacent,
                max_shift=cfg.step_retry_shift_cells * cell, parallel_cos=parallel,
            )
            cen = cen_unit
        # Brightness edges are squared to the outline: the creases give it more exactly than the trace.
        from_creases = crease_axes(creg, crease, regions.normals, regions.axes)
        axis_angles = np.where(np.isfinite(from_creases), from_creases, axis_angles)
    _, nearest = nb.tree.query(cpts, k=1)
    curv = nb.curvature[np.asarray(nearest, np.int64)]

    stage("brightness")
    if inten is not None:
        signs = brightness_signs(cpts, cen, creg, labels, inten, nb.tree, sc.brightness_radius,
                                 margin=0.5 * cell, threshold=cfg.brightness_threshold)
    else:
        signs = np.zeros(cpts.shape[0], np.int8)
    if inten is not None and cfg.albedo_edges:
        # Painted/albedo edges inside regions: normals point dark -> bright, so their sign is +1.
        visible = front_layer(pts, labels, nb.indices, regions.centroids, plane_n, cfg.albedo_layer_m, 3.0 * nb.spacing)
        apts, aen, areg = region_albedo_edges(
            pts, inten, [order[starts[r]:starts[r + 1]] for r in range(regions.sizes.size)], visible,
            regions.centroids, regions.axes, nb.spacing, sc.albedo_sigma, cfg.albedo_high, cfg.albedo_low,
            sc.albedo_min_length, cfg.contour_spacing_m,
            axis_angles=axis_angles, axis_snap_deg=cfg.albedo_axis_snap_deg,
            plane_normals=plane_n if cfg.albedo_panel_rims else None, layer_m=cfg.albedo_layer_m,
            panel_snap_deg=cfg.albedo_panel_snap_deg, panel_gap=cfg.albedo_panel_gap_m,
            corner_reach=cfg.albedo_corner_reach_m, marker_snap_deg=cfg.albedo_marker_snap_deg,
        )
        if apts.shape[0]:
            if cfg.albedo_mid_depth:
                # A panel's brightness edge is the rim of a small step: put it at mid-depth.
                apts = mid_layer_depth(apts, areg, pts, labels, visible, nb.tree, plane_n,
                                       cfg.albedo_mid_radius * nb.spacing, cfg.albedo_layer_m)
            _, nearest = nb.tree.query(apts, k=1)
            cpts = np.concatenate([cpts, apts])
            cen = np.concatenate([cen, aen])
            creg = np.concatenate([creg, areg])
            curv = np.concatenate([curv, nb.curvature[np.asarray(nearest, np.int64)]])
            signs = np.concatenate([signs, np.ones(apts.shape[0], np.int8)])
            crease = np.concatenate([crease, np.full(apts.shape[0], -1, np.int32)])
    if cfg.merge_double_m > 0 and cpts.shape[0]:
        # Support: crease-snapped points, then larger regions (better planes).
        priority = (crease >= 0) * (2.0 * pts.shape[0]) + regions.sizes[creg]
        keep, merged = merge_double_contours(cpts, creg, priority, cfg.merge_double_m)
        cpts, cen, creg, curv, signs = merged[keep], cen[keep], creg[keep], curv[keep], signs[keep]
    stage("done")
    if bar is not None:
        bar.close()
    if cpts.shape[0] == 0:
        raise MapBuildError(None, "no object contour found (all points coplanar without brightness edges, or only the scan's rim)")
    en_unit = cen / np.maximum(np.linalg.norm(cen, axis=1, keepdims=True), 1e-12)
    return ContourMap.from_points(
        cpts,
        edge_normal=en_unit.astype(np.float32),
        plane_normal=plane_n[creg].astype(np.float32),
        region_id=creg,
        curvature=curv.astype(np.float32),
        brightness_sign=signs,
    )
