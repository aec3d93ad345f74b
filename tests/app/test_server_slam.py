"""The viewer's SLAM mode without a browser: the mode dropdown switches engines, SLAM panels and the words about the MCI are drawn."""

import socket
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "slam"))
from slam_synthetic import make_recording  # noqa: E402

from app.engine import EventsOnlyEngine  # noqa: E402
from app.tracker_engine import TrackerEngine  # noqa: E402
from app.player import PlayerConfig  # noqa: E402
from app.server import AppConfig, ViewerApp  # noqa: E402
from app.slam_engine import SlamEngine  # noqa: E402
from evpose.io.h5 import write_recording_h5  # noqa: E402


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def viewer(tmp_path_factory):
    root = tmp_path_factory.mktemp("slamdata")
    write_recording_h5(root / "moving.h5", make_recording(duration_s=0.6, speed=1.5, seed=11))
    app = ViewerApp(AppConfig(data=[root], port=free_port(), export_dir=tmp_path_factory.mktemp("exports"), player=PlayerConfig(prefetch=False)))
    yield app
    app.stop()


def test_mode_dropdown_switches_to_slam_and_shows_mci_scores_and_map(viewer):
    viewer.player.wait_idle()
    assert not isinstance(viewer.player.engine, SlamEngine)
    assert viewer.set_mode("slam")
    viewer.player.wait_idle()
    assert isinstance(viewer.player.engine, SlamEngine)
    assert "Tracking needs a map" not in viewer.rec_info.content  # SLAM needs none
    assert "SlamViewConfig" in viewer.param_info.content or "SLAM mode" in viewer.param_info.content
    for _ in range(60):
        viewer.player.step_forward()
    viewer.player.wait_idle()
    f = viewer.last_frame
    assert f.slam is not None and f.index == 60
    import re

    # Between two MCIs the last MCI, its hypothesis scores and the current map stay shown.
    assert re.search(r"MCI at [\d.]+ s hypothesis scores \(mean local STD\): .*H\d\** \d", viewer.slam_info.content), viewer.slam_info.content
    assert not viewer.slam_info.content.startswith("map 0: 0 points")
    assert viewer.image_handles["MCI + tracked features"].image.shape[2] == 3
    assert any(k.startswith("slam_map/") for k in viewer.scene._nodes)  # the growing map is drawn
    path = viewer.export("trajectory")
    assert path is not None and len([ln for ln in path.read_text().splitlines() if not ln.startswith("#")]) >= 2


def test_slam_maps_are_shown_on_the_ground_truth_and_the_toggle_shows_them_raw(viewer):
    viewer.set_mode("slam")
    for _ in range(80):
        viewer.player.step_forward()
    viewer.player.wait_idle()
    f = viewer.last_frame
    view = f.slam.atlas[-1]
    assert view.alignment is not None and "aligned to the **ground truth**" in viewer.slam_info.content
    node = viewer.scene._nodes[f"slam_map/{view.map_id}"]
    assert np.allclose(node.points, view.alignment.points(view.points), rtol=2e-3, atol=2e-3)
    viewer.toggle_boxes["slam_aligned"].value = False  # as a click does: the callback redraws on the player thread
    viewer._set_toggle("slam_aligned", False)
    viewer.player.wait_idle()
    node = viewer.scene._nodes[f"slam_map/{view.map_id}"]
    assert np.allclose(node.points, view.points, rtol=2e-3, atol=2e-3) and "own frame" in viewer.slam_info.content
    viewer._set_toggle("slam_aligned", True)
    viewer.player.wait_idle()
    # The pose error is measured after the same alignment (it was empty: map-frame poses against the ground truth).
    from app.plots import SLAM_POSE_ERROR

    labels, plot = viewer.plots.handles[SLAM_POSE_ERROR]
    note = viewer.plots.notes.get(SLAM_POSE_ERROR)
    assert np.isfinite(plot.data[1]).sum() >= 2 and plot.visible and (note is None or not note.visible)


def test_only_the_modes_own_image_panels_are_shown_and_teaching_says_slam_runs_no_tracker_stage(viewer):
    viewer.set_mode("slam")
    viewer.player.step_forward()
    viewer.player.wait_idle()
    assert viewer.images_note.visible and not viewer.image_handles["SP-TS positive"].visible  # frozen otherwise
    assert viewer.image_handles["MCI + tracked features"].visible and not viewer.teaching_image.visible
    viewer.stage_dropdown.value = "TDF"
    viewer._set_stage("TDF")
    viewer.player.wait_idle()
    viewer.layout_gui.set_visible("teaching", True)
    viewer.player.wait_idle()
    assert "SLAM mode runs no map-based tracking" in viewer.teaching_text.content and "_Image:" not in viewer.teaching_text.content
    viewer.set_mode("tracking")
    viewer.player.step_forward()
    viewer.player.wait_idle()
    assert not viewer.images_note.visible and viewer.image_handles["SP-TS positive"].visible and viewer.teaching_image.visible
    assert not viewer.image_handles["MCI + tracked features"].visible and "SLAM mode shows here" in viewer.slam_info.content
    viewer.layout_gui.set_visible("teaching", False)


def test_back_to_tracking_mode_without_a_map_is_the_events_view(viewer):
    assert viewer.set_mode("tracking")
    viewer.player.step_forward()
    viewer.player.wait_idle()
    assert isinstance(viewer.player.engine, (EventsOnlyEngine, TrackerEngine)) and viewer.last_frame.slam is None
    if isinstance(viewer.player.engine, EventsOnlyEngine):  # no map here: the empty pose-error plot says why instead
        viewer.player.step_forward()
        viewer.player.wait_idle()
        note = viewer.plots.notes["pose error"]
        assert note.visible and "Tracking needs a map" in note.content and not viewer.plots.handles["pose error"][1].visible
    assert not viewer.set_mode("lidar")


def test_slam_mode_without_imu_for_event_inertial_says_why():
    from app.slam_engine import slam_engine_factory
    from app.slam_engine import SlamViewConfig
    from evpose.slam import SlamConfig, SlamMode

    rec = make_recording(duration_s=0.1, speed=1.5, seed=1)
    rec.imu = None
    eng = slam_engine_factory(rec)(SlamViewConfig(slam=SlamConfig(mode=SlamMode.EVENT_INERTIAL)))
    assert isinstance(eng, EventsOnlyEngine) and "SLAM cannot start" in eng.explanation and "IMU" in eng.explanation
    assert np.asarray(eng.step().ts_positive).ndim == 2
