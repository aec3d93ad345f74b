"""3D scene: trajectories go out in bounded chunks (unchanged chunks are not resent), small frustum texture, map colours."""

import numpy as np
import pytest
import viser

from app.bench import free_port
from app.frame import StepSummary
from app.scene import (FRUSTUM_IMAGE_WIDTH, GREY, SLAM_POINT_RANGE, SLAM_POINT_SPACING, TRAJECTORY_CHUNK, SceneView, frustum_image,
                       keyframe_axes_length, map_colours, slam_point_size, trajectory_chunks)


def _summaries(n: int) -> list[StepSummary]:
    out = []
    for i in range(n):
        T = np.eye(4)
        T[:3, 3] = (0.01 * i, np.sin(0.01 * i), 1.0)
        out.append(StepSummary(i, 5000 * i, T, T.copy(), "ok", {}, {}))
    return out


@pytest.fixture(scope="module")
def scene():
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    yield SceneView(server)
    server.stop()


def test_trajectory_chunks_join_into_the_whole_polyline():
    p = np.random.default_rng(0).random((600, 3))
    chunks = trajectory_chunks(p, 256)
    assert [len(c) for c in chunks] == [256, 256, 87]
    assert np.allclose(np.concatenate(chunks), np.stack([p[:-1], p[1:]], axis=1))


def test_growing_history_resends_only_the_newest_chunk_and_seeking_back_removes_chunks(scene):
    hist = _summaries(TRAJECTORY_CHUNK * 2 + 40)
    scene._trajectories(hist[:TRAJECTORY_CHUNK + 10])
    first = scene._nodes["fused/0"]
    assert set(k for k in scene._nodes if k.startswith("fused/")) == {"fused/0", "fused/1"}
    scene._trajectories(hist)
    assert scene._nodes["fused/0"] is first  # a complete chunk is never resent
    assert {"fused/1", "fused/2", "reg/2"} <= set(scene._nodes)
    scene._trajectories(hist[:50])  # a seek back
    assert scene._nodes["fused/0"] is not first
    assert not any(k in scene._nodes for k in ("fused/1", "fused/2", "reg/1"))
    scene.toggles.fused = False
    scene.apply_toggles()
    assert scene._nodes["fused/0"].visible is False and scene._nodes["reg/0"].visible is True


def test_frustum_image_is_shrunk_and_bright_on_edges():
    tdf = np.ones((260, 346), np.float32)
    tdf[100:110, :] = 0.0
    img = frustum_image(tdf)
    assert img.shape[1] == FRUSTUM_IMAGE_WIDTH and img.dtype == np.uint8
    assert frustum_image(np.ones((30, 40), np.float32)).shape == (30, 40, 3)


def test_map_colours_from_a_grey_base_equal_the_plain_ones():
    from app.frame import Frame
    from evpose.core.events import EventArray

    z = np.zeros((4, 4), np.float32)
    f = Frame(0, 0, z, z, z, EventArray.empty(), EventArray.empty(), visible_index=np.array([1, 2, 5]),
              point_index=np.array([2, 5, 7]), predicted_polarity=np.array([1, -1, 0], np.int8))
    base = np.tile(GREY, (10, 1))
    a, b = map_colours(10, f), map_colours(10, f, base)
    assert np.array_equal(a, b) and np.all(base == GREY)


def test_far_map_points_are_sent_at_full_precision_without_overflow(scene):
    import warnings

    from evpose.core.contour_map import ContourMap

    pts = np.array([[0.0, 0.0, 0.0], [1e5, 2.0, 0.0], [0.123456, 10.004, 0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # float16 would overflow at 1e5 ("overflow encountered in cast")
        scene.load(ContourMap.from_points(pts), None, None, None)
    sent = np.asarray(scene._nodes["map"].points)
    assert sent.dtype == np.float32 and np.allclose(sent, pts, rtol=1e-6)


def test_slam_map_points_are_narrower_than_their_spacing_within_the_scene_bounds():
    grid = np.stack(np.meshgrid(np.arange(20), np.arange(20), [0.0]), -1).reshape(-1, 3) * 0.075  # 7.5 cm apart
    extent = 8.0  # the landing demo's flight: 0.008 x 8 m = 6.4 cm points would nearly touch
    size = slam_point_size(grid, extent)
    assert size == pytest.approx(SLAM_POINT_SPACING * 0.075)
    assert slam_point_size(grid * 100, extent) == pytest.approx(SLAM_POINT_RANGE[1] * extent)  # sparse: capped
    assert slam_point_size(grid / 100, extent) == pytest.approx(SLAM_POINT_RANGE[0] * extent)  # dense: still visible
    assert slam_point_size(grid[:1], extent) == pytest.approx(SLAM_POINT_RANGE[1] * extent)


def test_turning_follow_off_puts_the_camera_back_on_the_overview(scene):
    from evpose.core.contour_map import ContourMap

    scene.load(ContourMap.from_points(np.array([[0.0, 0.0, 0.0], [4.0, 2.0, 1.0]])), None, None, None)
    overview = np.array(scene.server.initial_camera.position)
    scene.toggles.follow = True
    scene.apply_toggles()
    pose = np.eye(4)
    pose[:3, 3] = (1.0, 1.0, 0.5)
    scene.follow(pose)
    scene.server.initial_camera.position = (9.0, 9.0, 9.0)  # as a browser's camera left where follow put it
    scene.toggles.follow = False
    scene.apply_toggles()
    assert np.allclose(scene.server.initial_camera.position, overview)


def test_keyframe_axes_are_shorter_than_the_steps_between_keyframes_within_the_scene_bounds():
    line = np.outer(np.arange(10), [0.05, 0.0, 0.0])  # keyframes 5 cm apart
    assert keyframe_axes_length(line, 2.0) == pytest.approx(0.03)
    assert keyframe_axes_length(line * 100, 2.0) == pytest.approx(0.08)  # far apart: capped at 0.04 x extent
    assert keyframe_axes_length(line / 100, 2.0) == pytest.approx(0.02)  # bunched: still visible
    assert keyframe_axes_length(line[:1], 2.0) == pytest.approx(0.08)


def test_toggles_applied_while_the_player_thread_replaced_a_node_skip_the_removed_one(scene):
    # A layout's checkboxes are set on the GUI thread while the player thread redraws (session 28's suite: "Cannot
    # assign to 'visible' on a removed BatchedAxesHandle"); the replacement is drawn with the toggles already set.
    scene._trajectories(_summaries(5))
    removed = scene._nodes["fused/0"]
    removed.remove()
    scene.toggles.fused = False
    try:
        scene.apply_toggles()
        assert all(not n.visible for k, n in scene._nodes.items() if k.startswith("fused/") and n is not removed)
    finally:
        scene.toggles.fused = True
        scene._nodes.pop("fused/0", None)
        scene.apply_toggles()
