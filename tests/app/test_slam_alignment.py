"""SLAM maps on the ground truth: evo's Umeyama alignment per atlas map (as ``evpose eval --atlas --correct-scale``),
applied to points, keyframes and trajectory for display only, with the raw frame a toggle away."""

import socket
import sys
from pathlib import Path

import numpy as np
import pytest
import viser
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "slam"))
from slam_synthetic import make_recording  # noqa: E402

from app.frame import Frame, SlamView  # noqa: E402
from app.scene import SceneView  # noqa: E402
from app.slam_alignment import AtlasAligner, alignment_note  # noqa: E402
from evpose.eval.sim3_alignment import Sim3, align_to_ground_truth  # noqa: E402
from app.slam_engine import SlamEngine, slam_markdown  # noqa: E402
from tests.app.test_slam_engine import all_steps  # noqa: E402
from evpose.core.events import EventArray  # noqa: E402
from evpose.core.trajectory import Trajectory  # noqa: E402
from evpose.eval.slam_metrics import atlas_metrics  # noqa: E402
from evpose.slam.atlas import Atlas, Keyframe, MapPoint  # noqa: E402

TRUE = Sim3(Rotation.from_euler("xyz", [0.3, -0.5, 1.1]).as_matrix(), np.array([2.0, -1.0, 0.5]), 3.5)
"""Map -> ground truth of the synthetic maps below."""


def _ground_truth(n=200) -> Trajectory:
    t = np.linspace(0.0, 2.0, n)
    pos = np.stack([np.cos(t), np.sin(1.5 * t), 0.3 * t], axis=1)
    rot = Rotation.from_rotvec(np.stack([0.1 * t, 0.2 * np.sin(t), 0.05 * t], axis=1))
    return Trajectory.from_arrays((t * 1e6).astype(np.int64), pos, rot.as_quat())


def _to_map(T: np.ndarray) -> np.ndarray:
    """Ground-truth poses -> the map frame of TRUE (its inverse)."""
    Ri, si = TRUE.R.T, 1.0 / TRUE.s
    out = T.copy()
    out[..., :3, :3] = Ri @ T[..., :3, :3]
    out[..., :3, 3] = si * (T[..., :3, 3] - TRUE.t) @ Ri.T
    return out


def _atlas(gt: Trajectory) -> Atlas:
    """Two maps seeing the ground truth's first and second half, each in TRUE's map frame."""
    atlas = Atlas()
    for lo, hi in ((0, 100), (100, 200)):
        m = atlas.new_map()
        T = _to_map(gt.matrices()[lo:hi])
        m.keyframes = [Keyframe(k, int(gt.t[lo + k]), T[k]) for k in range(0, hi - lo, 25)]
        for i in range(hi - lo):
            m.add_pose(int(gt.t[lo + i]), T[i])
        m.points = {j: MapPoint(j, T[j, :3, 3] + 0.1) for j in range(0, hi - lo, 10)}
    return atlas


def test_umeyama_recovers_a_known_similarity_for_points_and_poses():
    gt = _ground_truth()
    est = Trajectory.from_matrices(gt.t, _to_map(gt.matrices()))
    sim = align_to_ground_truth(est, gt)
    assert sim.s == pytest.approx(TRUE.s) and np.allclose(sim.R, TRUE.R) and np.allclose(sim.t, TRUE.t)
    assert np.allclose(sim.points(est.position), gt.position)
    assert np.allclose(sim.poses(est.matrices()), gt.matrices())
    rigid = align_to_ground_truth(est, gt, correct_scale=False)
    assert rigid.s == 1.0 and not np.allclose(rigid.points(est.position), gt.position)


def test_no_alignment_without_ground_truth_enough_poses_or_a_non_degenerate_path():
    gt = _ground_truth()
    est = Trajectory.from_matrices(gt.t, _to_map(gt.matrices()))
    assert align_to_ground_truth(est, None) is None
    assert align_to_ground_truth(est[:2], gt) is None
    line = gt.matrices()[:50].copy()
    line[:, :3, 3] = np.outer(np.linspace(0, 1, 50), [1.0, 2.0, 0.5])
    assert align_to_ground_truth(Trajectory.from_matrices(gt.t[:50], line), gt) is None
    late = Trajectory.from_matrices(gt.t + 10_000_000, est.matrices())  # outside the ground truth's span
    assert align_to_ground_truth(late, gt) is None


def test_each_atlas_map_is_aligned_as_the_atlas_metrics_align_it_and_old_maps_are_computed_once():
    gt = _ground_truth()
    atlas = _atlas(gt)
    aligner = AtlasAligner(gt)
    views = aligner.views(atlas)
    assert [(v.map_id, v.active) for v in views] == [(0, False), (1, True)]
    metrics = atlas_metrics(atlas.trajectories(), gt, correct_scale=True)
    assert [v.alignment.s for v in views] == pytest.approx([m.scale for m in metrics.maps], rel=1e-12)
    for v, (lo, hi) in zip(views, ((0, 100), (100, 200))):
        assert np.allclose(v.alignment.points(v.trajectory), gt.position[lo:hi])
        assert np.allclose(v.alignment.poses(v.keyframe_poses)[:, :3, 3], gt.position[lo:hi:25])
    again = aligner.views(atlas)
    assert again[0] is views[0] and again[1] is not views[1]
    atlas.maps[1].imu_initialised = True  # a metric (IMU-initialised) map is aligned rigidly
    assert aligner.views(atlas)[1].alignment.s == 1.0 and not aligner.views(atlas)[1].scaled


def test_only_finished_maps_are_drawn_with_their_poses_re_solved(monkeypatch):
    from evpose.slam.atlas import SlamMap

    calls, trajectory = [], SlamMap.trajectory

    def spy(self, refined=True, refit=True):
        calls.append((self.id, refined, refit))
        return trajectory(self, refined, refit)

    monkeypatch.setattr(SlamMap, "trajectory", spy)
    gt = _ground_truth()
    AtlasAligner(gt).views(_atlas(gt))
    assert calls == [(0, True, True), (1, True, False)]  # the active map is drawn anew at every step


def test_the_words_say_the_alignment_uses_the_ground_truth():
    gt = _ground_truth()
    views = AtlasAligner(gt).views(_atlas(gt))
    text = alignment_note(views, aligned=True, has_ground_truth=True)
    assert "ground truth" in text and "Sim(3), scale 3.5 m/unit" in text and "SLAM never sees" in text
    assert "own frame" in alignment_note(views, aligned=False, has_ground_truth=True)
    assert "no ground truth" in alignment_note(AtlasAligner(None).views(_atlas(gt)), aligned=True, has_ground_truth=False)


@pytest.fixture(scope="module")
def scene():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    yield SceneView(server)
    server.stop()


def _slam_frame(views, pose=None) -> Frame:
    z = np.zeros((4, 4), np.float32)
    v = SlamView(None, None, "", {}, None, None, False, views[-1].map_id if views else -1, None, None, atlas=views,
                 has_ground_truth=True)
    return Frame(0, 0, z, z, z, EventArray.empty(), EventArray.empty(), pose=pose, status="ok", slam=v)


def test_the_scene_draws_every_map_aligned_or_raw_and_resends_only_the_active_one(scene):
    gt = _ground_truth()
    views = AtlasAligner(gt).views(_atlas(gt))
    pose = _to_map(gt.matrices()[150:151])[0]
    scene.toggles.slam_aligned = True
    scene.update(_slam_frame(views, pose), history=[])
    for i, (lo, hi) in enumerate(((0, 100), (100, 200))):
        assert np.allclose(scene._nodes[f"slam_map/{i}"].points, views[i].alignment.points(views[i].points), rtol=2e-3, atol=2e-3)  # sent as float16
        assert len(scene._nodes[f"slam_traj/{i}"].points) == hi - lo - 1
    assert np.allclose(scene.slam_pose(_slam_frame(views, pose)), gt.matrices()[150])
    old, active = scene._nodes["slam_map/0"], scene._nodes["slam_map/1"]
    scene.update(_slam_frame(views, pose), history=[])
    assert scene._nodes["slam_map/0"] is old and scene._nodes["slam_map/1"] is not active
    scene.toggles.slam_aligned = False  # raw: each map in its own frame, the camera too
    scene.update(_slam_frame(views, pose), history=[])
    assert np.allclose(scene._nodes["slam_map/0"].points, views[0].points, rtol=2e-3, atol=2e-3)
    assert np.array_equal(scene.slam_pose(_slam_frame(views, pose)), pose)
    scene.update(_slam_frame(views[:1]), history=[])  # after a seek back, before map 1 began
    assert "slam_map/1" not in scene._nodes and "slam_map/0" in scene._nodes
    scene.toggles.slam_aligned = True


def test_slam_engine_frames_carry_their_maps_aligned_to_the_recordings_ground_truth():
    rec = make_recording(duration_s=0.6, speed=1.5, seed=11)
    eng = SlamEngine(rec)
    frames = all_steps(eng)
    assert frames[0].slam.map_id == -1 and slam_markdown(frames[0]).startswith("no map yet")  # not "map -1: 0 points"
    last = frames[-1]
    assert last.slam.has_ground_truth and last.slam.atlas and last.slam.atlas[-1].active
    # The active map is drawn without the final re-solve of its PnP poses (done once the map is finished), so the
    # metrics to compare with are of the same trajectories.
    maps = [m for m in eng.slam.atlas.maps if m.traj_t]
    metrics = atlas_metrics([m.trajectory(refit=m is not eng.slam.atlas.maps[-1]) for m in maps], rec.ground_truth,
                            correct_scale=True)
    aligned = [v for v in last.slam.atlas if v.alignment is not None]
    assert aligned and [v.alignment.s for v in aligned] == pytest.approx([m.scale for m in metrics.maps], rel=1e-9)
    v = aligned[-1]
    traj = eng.slam.atlas.maps[v.map_id].trajectory()
    err = np.linalg.norm(v.alignment.points(v.trajectory) - rec.ground_truth.interpolate(traj.t).position, axis=1)
    path = np.linalg.norm(np.diff(rec.ground_truth.interpolate(traj.t).position, axis=0), axis=1).sum()
    assert np.sqrt(np.mean(err**2)) < 0.1 * path  # on the ground truth, not at an arbitrary place and scale
    text = slam_markdown(last, aligned=True)
    assert "aligned to the **ground truth**" in text and "SLAM never sees" in text
    assert "own frame" in slam_markdown(last, aligned=False)
