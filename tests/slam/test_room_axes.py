import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.bundle_adjustment import local_bundle_adjustment
from evpose.slam.room_axes import RoomAxesSettings, measure_room_rotation, room_frame, room_priors

K = np.array([[247.0, 0, 172.5], [0, 247.0, 129.5], [0, 0, 1]])
# Camera looking along world +x, its y axis down (world z up); the room's axes are the world's.
R_LEVEL = np.array([[0, 0, 1.0], [-1, 0, 0], [0, -1, 0]])


def _camera(pitch_deg: float, yaw_deg: float, roll_deg: float) -> np.ndarray:
    return Rotation.from_euler("z", yaw_deg, degrees=True).as_matrix() @ R_LEVEL @ Rotation.from_euler(
        "xz", [pitch_deg, roll_deg], degrees=True).as_matrix()


def _render_box_room(R_wc: np.ndarray) -> np.ndarray:
    """An MCI-like image of thin ridges along the edges of two axis-aligned boxes, a wall picture ahead and the
    floor's edges along the two side walls."""
    img = np.zeros((260, 346), np.uint8)
    lines = [(np.array([1.5, y, -1.0]), np.array([6.0, y, -1.0])) for y in (-2.0, 2.0)]
    for x0, y0, z0, sx, sy, sz in ((3.0, -1.2, -1.0, 0.8, 0.6, 0.9), (4.0, 0.6, -1.0, 0.6, 1.0, 0.5), (5.0, -0.5, 0.3, 0.01, 1.2, 0.7)):
        c = np.array([[x0 + i * sx, y0 + j * sy, z0 + k * sz] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
        for a in range(8):
            for b in range(a + 1, 8):
                if bin(a ^ b).count("1") == 1:
                    lines.append((c[a], c[b]))
    for P, Q in lines:
        pc = np.stack([P, Q]) @ R_wc  # world -> camera (camera at the origin)
        if (pc[:, 2] < 0.5).any():
            continue
        uv = pc @ K.T
        uv = uv[:, :2] / uv[:, 2:]
        cv2.line(img, tuple(np.round(uv[0] * 16).astype(int)), tuple(np.round(uv[1] * 16).astype(int)), 255, 1,
                 cv2.LINE_AA, shift=4)
    return cv2.GaussianBlur(img, (3, 3), 0.8)


def _error_deg(R: np.ndarray, R_true: np.ndarray) -> float:
    """Angle between two camera-from-room rotations up to the room's 90-deg yaw symmetry."""
    best = 180.0
    for k in range(4):
        Z = Rotation.from_euler("z", 90 * k, degrees=True).as_matrix()
        best = min(best, np.degrees(np.linalg.norm(Rotation.from_matrix(R @ (R_true @ Z).T).as_rotvec())))
    return best


def test_measure_room_rotation_recovers_all_three_angles_without_a_guess():
    R_wc = _camera(-10.0, 20.0, 3.0)
    R, H = measure_room_rotation(_render_box_room(R_wc), K)
    assert R is not None
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-9)
    assert _error_deg(R, R_wc.T) < 0.5
    assert np.all(np.linalg.eigvalsh(H) > 0)


def test_measure_room_rotation_needs_segments_along_every_axis():
    R, H = measure_room_rotation(np.zeros((260, 346), np.uint8), K)
    assert R is None and H is None
    # Only vertical ridges: pitch and roll would be seen, yaw not; the measurement is dropped.
    img = np.zeros((260, 346), np.uint8)
    for x in (60, 140, 250, 300):
        cv2.line(img, (x, 30), (x + 3, 220), 255, 1, cv2.LINE_AA)
    assert measure_room_rotation(img, K) == (None, None)


def test_measure_room_rotation_drops_a_scene_whose_edges_are_not_mostly_along_three_axes():
    R_wc = _camera(-10.0, 20.0, 3.0)
    room = _render_box_room(R_wc)
    cluttered = room.copy()
    rng = np.random.default_rng(1)
    for _ in range(12):  # straight edges at random angles, like a landing's ground texture
        c, a, h = rng.uniform([20, 20], [326, 240]), rng.uniform(0, np.pi), rng.uniform(20, 50)
        d = h * np.array([np.cos(a), np.sin(a)])
        cv2.line(cluttered, tuple(np.round(c + d).astype(int)), tuple(np.round(c - d).astype(int)), 255, 1, cv2.LINE_AA)
    assert measure_room_rotation(cluttered, K, RoomAxesSettings(min_axis_share=0.0))[0] is not None  # 3 deg off
    assert measure_room_rotation(cluttered, K) == (None, None)  # about 73 % of its segment length explained
    R, _ = measure_room_rotation(room, K)
    assert R is not None and _error_deg(R, R_wc.T) < 0.5


def _keyframe(kid: int, R_wc_est: np.ndarray, R_cm: np.ndarray) -> Keyframe:
    T = np.eye(4)
    T[:3, :3] = R_wc_est
    return Keyframe(kid, kid, T, R_cm=R_cm, R_cm_info=np.eye(3) / np.radians(0.3) ** 2)


def test_room_frame_takes_the_consensus_up_to_the_yaw_symmetry_and_drops_a_mislabelled_keyframe():
    M_true = Rotation.from_euler("z", 30, degrees=True).as_matrix()  # map-from-room
    Z90 = Rotation.from_euler("z", 90, degrees=True).as_matrix()
    kfs = []
    for kid, yaw in enumerate((0.0, 10.0, 25.0)):
        R_wc = Rotation.from_euler("zx", [yaw, -100.0], degrees=True).as_matrix()
        R_cm = R_wc.T @ M_true
        kfs.append(_keyframe(kid, R_wc, R_cm @ Z90 if kid == 1 else R_cm))  # keyframe 1 labelled 90 deg round
    R_bad = kfs[0].T_wc[:3, :3].T @ M_true @ Rotation.from_euler("x", 20, degrees=True).as_matrix()
    kfs.append(_keyframe(3, kfs[0].T_wc[:3, :3], R_bad))
    M, labels = room_frame(kfs)
    assert np.allclose(M, M_true, atol=1e-9)
    assert set(labels) == {0, 1, 2}
    pri = room_priors(kfs, M, labels, 0.0)
    assert set(pri) == {0, 1, 2}
    for kf in kfs[:3]:
        assert np.allclose(pri[kf.id][0][:3, :3], kf.T_wc[:3, :3], atol=1e-9)  # these poses agree with M already
    C4 = room_priors(kfs, M, labels, 0.0, gain=4.0)[0][1]
    assert np.allclose(C4[:3, :3], pri[0][1][:3, :3] / 4.0) and np.allclose(C4[3:, 3:], pri[0][1][3:, 3:])
    assert room_frame(kfs[:1]) == (None, {})


def _three_keyframe_map(tilt_deg: float) -> SlamMap:
    """Three keyframes 0.1 apart seeing 40 points; the newest turned ``tilt_deg`` about its x axis, its observations
    consistent with that pose."""
    rng = np.random.default_rng(0)
    m = SlamMap(0)
    X = rng.uniform([-1, -1, 3], [1, 1, 5], (40, 3))
    for i in range(3):
        T = np.eye(4)
        T[:3, 3] = [0.1 * i, 0, 0]
        if i == 2:
            T[:3, :3] = Rotation.from_euler("x", tilt_deg, degrees=True).as_matrix()
        m.keyframes.append(Keyframe(i, i, T))
    for j, x in enumerate(X):
        obs = {}
        for kf in m.keyframes:
            uv = K @ (kf.T_wc[:3, :3].T @ (x - kf.T_wc[:3, 3]))
            obs[kf.id] = uv[:2] / uv[2]
        m.points[j] = MapPoint(j, x.copy(), obs)
    return m


def test_local_ba_room_prior_pulls_a_turned_keyframe_towards_its_measured_rotation():
    for with_prior in (False, True):
        m = _three_keyframe_map(2.0)
        for kf in m.keyframes:
            kf.R_cm, kf.R_cm_info = np.eye(3), np.eye(3) / np.radians(0.01) ** 2  # every keyframe measured unturned
        M, labels = room_frame(m.keyframes)  # the turned keyframe agrees within 8 deg: M is 2/3 deg off
        pri = room_priors(m.keyframes, M, labels, 0.0) if with_prior else None
        local_bundle_adjustment(m, K, 3, 20, 2.0, n_fixed=2, attitude_priors=pri)
        turn = np.degrees(np.linalg.norm(Rotation.from_matrix(m.keyframes[2].T_wc[:3, :3]).as_rotvec()))
        # The images alone keep the turn they were made with; the prior takes most of it out.
        assert (turn < 1.0) if with_prior else (turn > 1.9)
