"""Events registered at their own timestamps: exact events put the pose back on the truth from a perturbed start, the
polarity leads (grazing surfaces', creases' and edges seen past apart) and the predicted polarity are honoured, a map line's own offset is learned but not a pose-like one,
and the tracker runs it in the fused modes only."""

import gtsam
import numpy as np
from tracker_synthetic import generate

from evpose.core.contour_map import ContourMap
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.contrast_leads import ContrastLeadConfig
from evpose.tracker.event_registration import EventRegistration, EventRegistrationConfig
from evpose.tracker.modes import MotionComponents
from evpose.tracker.tracker import Tracker

W, H, F = 160, 120, 100.0
K = np.array([[F, 0, (W - 1) / 2], [0, F, (H - 1) / 2], [0, 0, 1.0]])
DOWN = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 2.0], [0, 0, 0, 1.0]])
"""Camera 2 m above the ground looking straight down: 50 px per metre."""
TWIST = np.array([0.02, -0.03, 0.05, 0.4, -0.3, 0.1])
"""Body twist per second (rotation, translation): every edge moves in the image."""
T_REF = 1_000_000


def ground_lines() -> ContourMap:
    """Lines x = const (y from 0.1 to 0.7) and y = const (y < 0) on the ground, ~1 px samples, normals +x / +y: no
    line within 10 px of another, so every event's nearest point is on its own line."""
    s = np.linspace(-1.0, 1.0, 61)
    pts, normals, tangents = [], [], []
    for x in (-1.0, -0.4, 0.3, 0.9):
        pts.append(np.stack([np.full(s.size, x), 0.4 + 0.3 * s, np.zeros(s.size)], axis=1))
        normals.append(np.tile([1.0, 0.0, 0.0], (s.size, 1)))
        tangents.append(np.tile([0.0, 1.0, 0.0], (s.size, 1)))
    for y in (-0.6, -0.35, -0.1):
        pts.append(np.stack([1.3 * s, np.full(s.size, y), np.zeros(s.size)], axis=1))
        normals.append(np.tile([0.0, 1.0, 0.0], (s.size, 1)))
        tangents.append(np.tile([-1.0, 0.0, 0.0], (s.size, 1)))
    n, t = np.concatenate(normals), np.concatenate(tangents)
    return ContourMap.from_points(np.concatenate(pts), edge_normal=n, plane_normal=np.cross(n, t))


def pose_at(t_us: int) -> np.ndarray:
    return (gtsam.Pose3(DOWN) * gtsam.Pose3.Expmap(-TWIST * (T_REF - t_us) * 1e-6)).matrix()


def exact_events(cmap: ContourMap, lead_px: float = 0.0, polarity: int = 1, seed: int = 0, n: int = 3000):
    """Events exactly on the true lines at their own times over the last 5 ms (sub-pixel ideal coordinates), each moved
    ``lead_px`` along its edge's image motion: (x, y, t, p)."""
    rng = np.random.default_rng(seed)
    idx = rng.choice(len(cmap), n)
    t = np.sort(rng.integers(T_REF - 5000, T_REF + 1, idx.size))
    x, y = np.empty(idx.size), np.empty(idx.size)
    for j, (i, tj) in enumerate(zip(idx, t)):
        T = pose_at(int(tj))
        T2 = pose_at(int(tj) + 100)
        uv = [K[:2, :2] @ (c[:2] / c[2]) + K[:2, 2] for c in (np.linalg.inv(T2)[:3] @ np.r_[cmap.points[i], 1.0],
                                                                  np.linalg.inv(T)[:3] @ np.r_[cmap.points[i], 1.0])]
        flow = uv[0] - uv[1]
        tang = (np.linalg.inv(T)[:3, :3] @ np.cross(cmap.plane_normal[i], cmap.edge_normal[i]))[:2]
        n = np.array([-tang[1], tang[0]]) / np.linalg.norm(tang)
        x[j], y[j] = uv[1] + lead_px * np.sign(n @ flow) * n
    return x, y, t.astype(np.int64), np.full(idx.size, polarity, np.int8)


def perturbed() -> np.ndarray:
    return (gtsam.Pose3(pose_at(T_REF)) * gtsam.Pose3.Expmap(np.array([0.002, -0.001, 0.003, 0.004, -0.003, 0.002]))).matrix()


def error(T: np.ndarray) -> np.ndarray:
    return gtsam.Pose3.Logmap(gtsam.Pose3(pose_at(T_REF)).between(gtsam.Pose3(T)))


_NO_LONE = ContrastLeadConfig(lone_on_lead_px=0.0, lone_off_lead_px=0.0)
"""The lone-point lead (on by default) off: these synthetic events carry no pixel history, so every point is 'lone'."""


def registration(cmap: ContourMap, **config) -> EventRegistration:
    cfg = EventRegistrationConfig(**{"on_lead_px": 0.0, "off_lead_px": 0.0, "iterations": 5, "contrast": _NO_LONE, **config})
    return EventRegistration(cfg, W, H, cmap.points, np.cross(cmap.plane_normal, cmap.edge_normal), cmap.edge_normal)


def test_exact_events_bring_a_perturbed_pose_back_to_the_truth():
    cmap = ground_lines()
    reg = registration(cmap)
    out = reg.refine(perturbed(), np.arange(len(cmap)), None, *exact_events(cmap), T_REF, TWIST, K, None)
    assert out is not None and reg.last_events > 2000
    assert np.abs(error(perturbed())).max() > 1e-3
    assert np.abs(error(out[0])).max() < 2e-5
    assert np.all(np.linalg.eigvalsh(out[1]) > 0)


def test_the_lead_of_a_polarity_is_taken_out_and_ignoring_it_biases_the_pose():
    cmap = ground_lines()
    events = exact_events(cmap, lead_px=-0.3, polarity=-1)
    with_lead = registration(cmap, off_lead_px=-0.3).refine(perturbed(), np.arange(len(cmap)), None, *events, T_REF, TWIST, K, None)
    without = registration(cmap).refine(perturbed(), np.arange(len(cmap)), None, *events, T_REF, TWIST, K, None)
    assert np.abs(error(with_lead[0])).max() < 2e-5
    assert np.abs(error(without[0])).max() > 1e-3


def test_grazing_points_take_their_own_lead():
    # The x lines as the feet of vertical faces (plane normal along x: seen from 2 m above at |cos| < 0.45), the y
    # lines on the ground (|cos| > 0.85); their OFF events trail by -0.3 / -0.1 px.
    lines = ground_lines()
    vertical = lines.edge_normal[:, 0] == 1.0
    normals = np.where(vertical[:, None], [1.0, 0.0, 0.0], lines.plane_normal)
    cmap = ContourMap.from_points(lines.points, edge_normal=lines.edge_normal, plane_normal=normals)
    parts = [exact_events(ContourMap.from_points(lines.points[m], edge_normal=lines.edge_normal[m], plane_normal=lines.plane_normal[m]),
                          lead_px=lead, polarity=-1, seed=k) for k, (m, lead) in enumerate(((vertical, -0.3), (~vertical, -0.1)))]
    events = tuple(np.concatenate(a) for a in zip(*parts))
    tangents = np.cross(lines.plane_normal, lines.edge_normal)
    def run(**config):
        cfg = EventRegistrationConfig(**{"on_lead_px": 0.0, "off_lead_px": -0.1, "iterations": 5, "contrast": _NO_LONE, **config})
        reg = EventRegistration(cfg, W, H, cmap.points, tangents, cmap.edge_normal, plane_normal=cmap.plane_normal)
        return error(reg.refine(perturbed(), np.arange(len(cmap)), None, *events, T_REF, TWIST, K, None)[0])
    assert np.abs(run(grazing_max_cos=0.6, grazing_off_lead_px=-0.3)).max() < 2e-5
    assert np.abs(run()).max() > 3e-4  # off: one lead for both


def test_crease_points_take_their_own_lead():
    # The x lines as box tops' edges: each point has a twin of another region (a side face, plane normal along x) at
    # the same place; the y lines plain ground edges. Their OFF events trail by -0.3 / -0.1 px.
    lines = ground_lines()
    crease = lines.edge_normal[:, 0] == 1.0
    n_side = int(crease.sum())
    cmap = ContourMap.from_points(np.concatenate([lines.points, lines.points[crease]]),
                                  edge_normal=np.concatenate([lines.edge_normal, lines.edge_normal[crease]]),
                                  plane_normal=np.concatenate([lines.plane_normal, np.tile([1.0, 0.0, 0.0], (n_side, 1))]),
                                  region_id=np.r_[np.zeros(len(lines)), np.ones(n_side)])
    parts = [exact_events(ContourMap.from_points(lines.points[m], edge_normal=lines.edge_normal[m], plane_normal=lines.plane_normal[m]),
                          lead_px=lead, polarity=-1, seed=k) for k, (m, lead) in enumerate(((crease, -0.3), (~crease, -0.1)))]
    events = tuple(np.concatenate(a) for a in zip(*parts))
    tangents = np.concatenate([np.cross(lines.plane_normal, lines.edge_normal), np.tile([0.0, 1.0, 0.0], (n_side, 1))])
    def run(**config):
        cfg = EventRegistrationConfig(**{"on_lead_px": 0.0, "off_lead_px": -0.1, "iterations": 5, "grazing_max_cos": 0.0,
                                         "contrast": _NO_LONE, **config})
        reg = EventRegistration(cfg, W, H, cmap.points, tangents, cmap.edge_normal, plane_normal=cmap.plane_normal,
                                region_id=cmap.region_id)
        return error(reg.refine(perturbed(), np.arange(len(cmap)), None, *events, T_REF, TWIST, K, None)[0])
    assert np.abs(run(crease_radius_m=0.02, crease_off_lead_px=-0.3, beyond_off_lead_px=-0.1)).max() < 2e-5
    assert np.abs(run(crease_radius_m=0.0)).max() > 3e-4  # off: one lead for both


def test_points_whose_edge_the_camera_sees_past_take_their_own_lead():
    # One ground region, no crease: the camera (above the origin) sees past the lines x = -1 and -0.4 (outward normal
    # +x towards it) and the y lines (normal +y, all at y < 0) but not the lines x = 0.3 and 0.9; their OFF events
    # lead by +0.3 / trail by -0.1 px.
    lines = ground_lines()
    cmap = ContourMap.from_points(lines.points, edge_normal=lines.edge_normal, plane_normal=lines.plane_normal,
                                  region_id=np.zeros(len(lines)))
    beyond = (lines.edge_normal[:, 1] == 1.0) | (lines.points[:, 0] < 0)
    parts = [exact_events(ContourMap.from_points(lines.points[m], edge_normal=lines.edge_normal[m], plane_normal=lines.plane_normal[m]),
                          lead_px=lead, polarity=-1, seed=k) for k, (m, lead) in enumerate(((beyond, 0.3), (~beyond, -0.1)))]
    events = tuple(np.concatenate(a) for a in zip(*parts))
    tangents = np.cross(lines.plane_normal, lines.edge_normal)
    def run(**config):
        cfg = EventRegistrationConfig(**{"on_lead_px": 0.0, "off_lead_px": -0.1, "iterations": 5, "grazing_max_cos": 0.0,
                                         "contrast": _NO_LONE, **config})
        reg = EventRegistration(cfg, W, H, cmap.points, tangents, cmap.edge_normal, plane_normal=cmap.plane_normal,
                                region_id=cmap.region_id)
        return error(reg.refine(perturbed(), np.arange(len(cmap)), None, *events, T_REF, TWIST, K, None)[0])
    assert np.abs(run(crease_radius_m=0.02, beyond_off_lead_px=0.3)).max() < 2e-5
    assert np.abs(run(crease_radius_m=0.0, beyond_off_lead_px=0.3)).max() > 3e-4  # crease_radius_m off: one lead for all


def test_points_predicted_to_fire_the_other_polarity_take_none_of_the_events():
    cmap = ground_lines()
    reg = registration(cmap)
    on_only = np.ones(len(cmap), np.int8)
    assert reg.refine(perturbed(), np.arange(len(cmap)), -on_only, *exact_events(cmap, polarity=1), T_REF, TWIST, K, None) is None
    assert reg.last_events == 0
    assert reg.refine(perturbed(), np.arange(len(cmap)), on_only, *exact_events(cmap, polarity=1), T_REF, TWIST, K, None) is not None


def test_one_lines_own_offset_is_learned_and_a_pose_like_one_is_not():
    true_map = ground_lines()
    events = exact_events(true_map, n=20000)
    moved = true_map.points.copy()
    first = np.flatnonzero(true_map.points[:, 0] == -0.4)
    moved[first, 0] += 0.006  # 0.3 px along that line's normal
    built = ContourMap.from_points(moved, edge_normal=true_map.edge_normal, plane_normal=true_map.plane_normal)
    reg = registration(built, offset_gain=0.5)
    for _ in range(12):
        reg.refine(pose_at(T_REF), np.arange(len(built)), None, *events, T_REF, TWIST, K, None)
        reg.learn()
    x_lines = np.flatnonzero((true_map.edge_normal[:, 0] == 1.0) & (true_map.points[:, 0] != -0.4))
    y_lines = np.flatnonzero(true_map.edge_normal[:, 1] == 1.0)
    def moved_mean(rows):  # over the points that took events (a pixel's events go to its nearest point only)
        o = reg.offsets[rows]
        return o[o != 0].mean()

    # The line's displacement against the other x lines is learned back, less what the refined pose absorbs (moving
    # all the lines alike is a pose change, which is not learned); the y lines, which it does not involve, stay.
    assert moved_mean(first) - moved_mean(x_lines) < -0.003
    assert abs(moved_mean(y_lines)) < 0.0003


def test_the_tracker_registers_events_only_in_the_fused_modes_and_restores_its_offsets():
    rec, cmap, _ = generate(duration_s=0.1, seed=1)
    assert Tracker(TrackerConfig(mode=TrackerMode.STPE), cmap, rec.calibration).event_registration is None
    fused = Tracker(TrackerConfig(), cmap, rec.calibration, components=MotionComponents(drives_pose=True))
    assert fused.event_registration is not None
    off = TrackerConfig()
    off.event_registration.enabled = False
    assert Tracker(off, cmap, rec.calibration, components=MotionComponents(drives_pose=True)).event_registration is None
    fused.event_registration.offsets[:] = 0.001
    state = fused.snapshot()
    fused.event_registration.offsets[:] = 0.0
    fused.restore(state)
    assert np.all(fused.event_registration.offsets == 0.001)
    n = fused.event_registration._normals
    assert np.array_equal(fused.event_registration.points, np.asarray(cmap.points) + 0.001 * n)


def test_pixel_thresholds_shrink_on_coarser_sensors_only_when_a_reference_angle_is_set():
    from evpose.tracker.event_registration_config import scaled_to_pixel

    c = EventRegistrationConfig(angle_reference_pixel_mrad=4.05)
    assert scaled_to_pixel(c, 4.05) is c and scaled_to_pixel(c, 2.0) is c  # the reference sensor and finer ones
    angle = scaled_to_pixel(EventRegistrationConfig(angle_reference_pixel_mrad=4.05, angle_pixel_exponent=1.0), 5.83)
    assert np.isclose(angle.gate_px * 5.83, c.gate_px * 4.05) and np.isclose(angle.huber_px * 5.83, c.huber_px * 4.05)
    coarse = scaled_to_pixel(c, 5.83)  # the default exponent 2
    assert np.isclose(coarse.gate_px, c.gate_px * (4.05 / 5.83) ** 2) and np.isclose(coarse.huber_px, c.huber_px * (4.05 / 5.83) ** 2)
    assert np.isclose(coarse.covariance_scale, c.covariance_scale * (4.05 / 5.83) ** 4)  # the default exponent 4
    assert coarse.association_radius_px == c.association_radius_px and c.gate_px == EventRegistrationConfig().gate_px
    default = EventRegistrationConfig()  # off by default: the same thresholds at every resolution
    scaled = scaled_to_pixel(default, 5.83)
    assert (scaled.gate_px, scaled.huber_px, scaled.covariance_scale) == (default.gate_px, default.huber_px, default.covariance_scale)


def test_crease_off_lead_shrinks_with_the_pixel_on_coarser_sensors_only():
    from evpose.tracker.event_registration_config import scaled_to_pixel

    c = EventRegistrationConfig(crease_off_lead_pixel_exponent=1.0, coarse_on_lead_px=0.0)  # the ON leads: test_event_on_leads_s33
    assert scaled_to_pixel(c, 1e3 / 247.07) is c  # the simulated 346x260 camera (4.047 mrad) and the demos: as set
    assert scaled_to_pixel(c, 2.0) is c
    coarse = scaled_to_pixel(c, 5.83)  # its 240x180 sibling: a smaller lead, the same angle at exponent 1
    assert c.crease_off_lead_px < coarse.crease_off_lead_px < 0
    assert np.isclose(coarse.crease_off_lead_px * 5.83, c.crease_off_lead_px * c.lead_reference_pixel_mrad)
    steeper = scaled_to_pixel(EventRegistrationConfig(crease_off_lead_pixel_exponent=2.0, coarse_on_lead_px=0.0), 5.83)
    assert coarse.crease_off_lead_px < steeper.crease_off_lead_px < 0
    assert (coarse.off_lead_px, coarse.grazing_off_lead_px, coarse.crease_on_lead_px) == (c.off_lead_px, c.grazing_off_lead_px, c.crease_on_lead_px)
    for off in (EventRegistrationConfig(coarse_on_lead_px=0.0),
                EventRegistrationConfig(lead_reference_pixel_mrad=0.0, crease_off_lead_pixel_exponent=1.0, coarse_on_lead_px=0.0)):
        assert scaled_to_pixel(off, 5.83) is off  # off by default (the 3 s landing loses), or without a reference
