"""Teaching panel: every stage has an explanation and live figures from the step on screen."""

from app.engine import EventsOnlyEngine
from app.teaching import Stage, live_facts, teaching_markdown


def test_every_stage_explains_itself_with_live_numbers(bar_recording):
    eng = EventsOnlyEngine(bar_recording, explanation="tracking needs a map")
    frame = None
    for _ in range(10):
        frame = eng.step()
    for stage in Stage:
        text = teaching_markdown(stage, frame)
        assert stage.value in text and "step 9" in text
    assert "no map" in live_facts(Stage.REGISTRATION, frame)
    assert f"{frame.counts['events_in']} events arrived" in live_facts(Stage.EVENTS, frame)
    assert "Press play" in live_facts(Stage.TDF, None)


def test_the_image_caption_says_the_events_only_tdf_has_no_map_points_and_sp_ts_shows_both_polarities(bar_recording):
    from app.panels import panel_images
    from app.teaching import image_caption, live_image

    frame = EventsOnlyEngine(bar_recording).step()
    assert image_caption(Stage.TDF, frame) == "TDF (no map, so no points on it)"
    assert image_caption(Stage.EVENTS, frame) == "events kept / removed"
    assert "ON" in image_caption(Stage.SP_TS, frame) and "OFF" in image_caption(Stage.SP_TS, frame)
    imgs = panel_images(frame)
    both = live_image(Stage.SP_TS, frame, imgs, None)
    for name in ("SP-TS positive", "SP-TS negative"):  # each surface's pixels are in the one picture
        lit = imgs[name].max(axis=2) > 0
        assert lit.any() and (both[lit] >= imgs[name][lit]).all()


def test_the_explanations_name_what_the_tracker_runs_and_controls_that_exist():
    # Registration was said to be Gauss-Newton (it is Levenberg-Marquardt), fusion always a factor graph (an EKF and
    # modes without fusion exist), the removed events the noise filter's alone (the ego-motion filter's too).
    import re

    import evpose.tracker.registration as registration
    from app.config_gui import field_specs
    from app.teaching import EXPLANATIONS
    from evpose.tracker.config import TrackerConfig, TrackerMode

    assert "Levenberg-Marquardt" in registration.__doc__ and "Levenberg-Marquardt" in EXPLANATIONS[Stage.REGISTRATION]
    assert "ego-motion filter" in EXPLANATIONS[Stage.EVENTS] and "EKF" in EXPLANATIONS[Stage.FUSION]
    # As the Parameters panel shows them: folders, then the control's label ("blur [px]", the unit said once).
    labels = {tuple(p.replace("_", " ") for p in s.path[:-1]) + (s.label,) for s in field_specs(TrackerConfig())}
    modes = {m.value for m in TrackerMode}
    for stage, text in EXPLANATIONS.items():
        for ref in re.findall(r"`([^`]+)`", text):
            if ref in modes or any(c in ref for c in "-/(="):  # a mode, or a formula
                continue
            path = tuple(part.strip() for part in ref.split(">"))
            assert path in labels, f"{stage.value}: `{ref}` is no tracker parameter"


def test_the_text_says_which_3d_elements_it_speaks_of_are_hidden_and_where_to_tick_them():
    # The teaching layout hides the raw registrations and the IMU-rate poses; the fusion stage spoke of both.
    from app.layouts import LAYOUT_DIR, list_layouts
    from app.scene import SceneToggles

    teaching = list_layouts(LAYOUT_DIR)["teaching"].scene
    text = teaching_markdown(Stage.FUSION, None, toggles=teaching)
    assert "Hidden in the 3D view now: the raw registrations (purple) and the IMU-rate poses (small axes)" in text
    assert "tick *registration*, *imu poses* under **3D view** to show them" in text
    assert "Hidden" not in teaching_markdown(Stage.FUSION, None, toggles=SceneToggles())
    assert "tick *contour map*" in teaching_markdown(Stage.POLARITY, None, toggles=SceneToggles(contour_map=False))
    assert "Hidden" not in teaching_markdown(Stage.EVENTS, None, toggles=SceneToggles(contour_map=False, fused=False))


def test_previous_and_next_walk_the_stages_in_order_and_wrap_around():
    from app.teaching import stage_after

    order = list(Stage)
    assert order[0] == Stage.EVENTS and order[-1] == Stage.FUSION
    assert [stage_after(s, 1) for s in order] == order[1:] + order[:1]
    assert stage_after(Stage.EVENTS, -1) == Stage.FUSION
