"""The room-axes yaw search over all candidates at once picks what one candidate at a time picked (session 32)."""
import numpy as np

from evpose.slam import room_axes
from evpose.slam.room_axes import RoomAxesSettings, measure_room_rotation

from tests.slam.test_room_axes import K, _camera, _render_box_room


def _loop_search(n, length, up, cfg):
    """The per-candidate yaw search as it was before session 32 (the reference)."""
    h = np.array([1.0, 0, 0]) - up[0] * up
    h /= np.linalg.norm(h)
    best, R0 = -1.0, None
    for psi in np.radians(np.arange(0.0, 90.0, 1.0)):
        a = np.cos(psi) * h + np.sin(psi) * np.cross(up, h)
        R = np.c_[a, np.cross(up, a), up]
        score = float(length[np.min(np.abs(n @ R), axis=1) < np.sin(np.radians(cfg.search_gate_deg))].sum())
        if score > best:
            best, R0 = score, R
    return R0


def test_yaw_search_matches_the_one_candidate_at_a_time_search_bit_for_bit(monkeypatch):
    cfg = RoomAxesSettings()
    seen = []
    real_refine = room_axes._refine

    def spy(n, length, R0, gates, c):
        up = R0[:, 2]
        seen.append(np.array_equal(R0, _loop_search(n, length, up, c)))
        return real_refine(n, length, R0, gates, c)

    monkeypatch.setattr(room_axes, "_refine", spy)
    measured = 0
    for pitch, yaw, roll in ((-10, 20, 3), (5, -35, -2), (-20, 44, 1), (0, 0, 0), (12, 80, -4)):
        R, _ = measure_room_rotation(_render_box_room(_camera(pitch, yaw, roll)), K, cfg)
        measured += R is not None
    assert measured >= 3 and len(seen) >= 3 and all(seen)


def test_yaw_search_matches_on_random_segment_sets():
    cfg = RoomAxesSettings()
    rng = np.random.default_rng(5)
    for _ in range(300):
        n = rng.normal(size=(int(rng.integers(3, 40)), 3))
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        length = rng.uniform(15, 100, len(n))
        up = rng.normal(size=3) * [0.1, 1, 0.1]
        up /= np.linalg.norm(up)
        assert np.array_equal(room_axes._yaw_search(n, length, up, cfg), _loop_search(n, length, up, cfg))
