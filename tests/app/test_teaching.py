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


def test_the_image_line_says_the_events_only_tdf_has_no_map_points(bar_recording):
    frame = EventsOnlyEngine(bar_recording).step()
    assert "_Image: TDF + map points (no map, so no points on it)_" in teaching_markdown(Stage.TDF, frame)
    assert teaching_markdown(Stage.SP_TS, frame).endswith("_Image: SP-TS positive_")
