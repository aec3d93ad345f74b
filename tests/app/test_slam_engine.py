"""SLAM mode of the viewer: the engine equals a headless run_slam, seeks exactly, and its panels show the SLAM products."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "slam"))
from slam_synthetic import make_recording  # noqa: E402

from app.panels import SLAM_PANELS, panel_images  # noqa: E402
from app.slam_engine import SlamEngine, SlamViewConfig  # noqa: E402
from evpose.slam import SlamConfig, run_slam  # noqa: E402


def all_steps(eng: SlamEngine) -> list:
    """Every frame of ``eng``, stepped from where it stands to the end of its recording."""
    frames = []
    while (f := eng.step()) is not None:
        frames.append(f)
    return frames


def with_first_mci(frames) -> int:
    return next(f.index for f in frames if f.counts["mcis"])


@pytest.fixture(scope="module")
def moving():
    return make_recording(duration_s=0.6, speed=1.5, seed=11)


@pytest.fixture(scope="module")
def all_frames(moving):
    eng = SlamEngine(moving)
    return eng, all_steps(eng)


def test_slam_engine_steps_equal_a_headless_run(moving, all_frames):
    eng, frames = all_frames
    headless = run_slam(moving, SlamConfig(), chunk_us=eng.config.step_us)
    assert len(frames) == eng.n_steps and sum(f.counts["events_in"] for f in frames) == len(moving.events)
    assert sum(f.counts["mcis"] for f in frames) == len(headless.results) > 3
    # A step's frame shows the state after its last MCI: the headless result with the same running count.
    last_mci = np.cumsum([f.counts["mcis"] for f in frames]) - 1
    for f, i in zip(frames, last_mci):
        if f.counts["mcis"]:
            r = headless.results[i]
            assert f.status == r.status.value and f.slam.map_id == r.map_id and f.slam.hypothesis == r.hypothesis
            assert (f.pose is None) == (r.pose is None) and (f.pose is None or np.array_equal(f.pose, r.pose))
    assert any(f.slam.keyframe for f in frames) and any(f.slam.mci is not None and f.slam.hypothesis for f in frames)
    # A step without a new MCI keeps showing the last one (and says when it was made).
    quiet = next(f for f in frames[with_first_mci(frames):] if not f.counts["mcis"])
    assert quiet.slam.mci is not None and quiet.slam.mci_t_us < quiet.t_us
    last = frames[-1] if frames[-1].slam.map_points is not None else next(f for f in reversed(frames) if f.slam.map_points is not None)
    assert len(last.slam.map_points) > 0 and last.slam.keyframe_poses.shape[1:] == (4, 4)


def test_slam_engine_seek_lands_on_the_uninterrupted_state(moving, all_frames):
    _, frames = all_frames
    other = SlamEngine(moving, SlamViewConfig(snapshot_every=7))
    with_mci = [f.index for f in frames if f.counts["mcis"]]
    for k in (with_mci[-1], with_mci[0], len(frames) - 1, 3):
        f = other.seek(frames[k].t_us)
        assert f.index == k and f.t_us == frames[k].t_us and len(other.history) == k + 1
        assert f.status == frames[k].status
        assert (f.pose is None) == (frames[k].pose is None) and (f.pose is None or np.array_equal(f.pose, frames[k].pose))
        assert (f.slam.mci is None) == (frames[k].slam.mci is None)
        if f.slam.mci is not None:
            assert np.array_equal(f.slam.mci, frames[k].slam.mci) and f.slam.hypothesis_scores == frames[k].slam.hypothesis_scores


def test_slam_far_seeks_catch_up_in_slices_to_the_uninterrupted_state(moving, all_frames):
    _, frames = all_frames
    other = SlamEngine(moving, SlamViewConfig(snapshot_every=7))
    other.step()
    k = len(frames) - 2
    t = frames[k].t_us
    assert other.catch_up_steps(t) == k - 1 and other.catch_up_progress(t)[1] == pytest.approx((t - moving.t_start_us) / 1e6)
    slices = 1
    while not other.catch_up(t, 10):
        slices += 1
    assert slices == -(-(k - 1) // 10) and other.step_count == k and other.catch_up_steps(t) == 0
    f = other.seek(t)
    assert f.index == k and f.status == frames[k].status and len(other.history) == k + 1
    assert (f.pose is None) == (frames[k].pose is None) and (f.pose is None or np.array_equal(f.pose, frames[k].pose))
    # Back to an earlier step: from the snapshot before it, at most ``snapshot_every`` steps.
    assert other.catch_up_steps(frames[30].t_us) == 30 - 28


def test_slam_panels_show_tiny_frame_mci_with_features_and_events(all_frames):
    _, frames = all_frames
    f = next(f for f in frames if f.slam.mci is not None and f.slam.features is not None and len(f.slam.features))
    imgs = panel_images(f)
    assert tuple(imgs) == SLAM_PANELS
    for img in imgs.values():
        assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    mci = imgs["MCI + tracked features"]
    green, yellow = (mci == [40, 230, 60]).all(axis=2).any(), (mci == [250, 210, 0]).all(axis=2).any()
    assert green or yellow
    assert imgs["tiny frame"].max() > 0


def test_event_inertial_slam_engine_without_imu_is_an_input_error(moving):
    from dataclasses import replace

    from evpose.errors import InputError
    from evpose.slam import SlamMode

    rec = replace(moving, imu=None)
    with pytest.raises(InputError, match="IMU"):
        SlamEngine(rec, SlamViewConfig(slam=SlamConfig(mode=SlamMode.EVENT_INERTIAL)))


def test_slam_export_is_the_active_maps_refined_trajectory_like_the_cli(moving, all_frames):
    eng, _ = all_frames
    headless = run_slam(moving, SlamConfig(), chunk_us=eng.config.step_us)
    exported, expected = eng.trajectory(), headless.atlas.active.trajectory(refined=True)
    assert len(exported) == len(expected) > 3
    assert np.array_equal(exported.t, expected.t) and np.array_equal(exported.matrices(), expected.matrices())


def test_strided_play_and_a_stretch_without_events_keep_every_step_exact(moving, all_frames):
    # Play strides over the steps it does not draw (their display products were most of an empty step's cost), and
    # inside a stretch without events the seek snapshots are shared, not copied: the same states all the same.
    import dataclasses

    from evpose.core.events import EventArray

    eng, frames = all_frames
    played = SlamEngine(moving)
    shown = [played.play_step(7) for _ in range(3)]
    assert [f.index for f in shown] == [6, 13, 20]
    assert [s.counts for s in played.history] == [f.counts for f in frames[:21]]
    assert np.array_equal(shown[-1].pose, frames[20].pose, equal_nan=True) if shown[-1].pose is not None else frames[20].pose is None
    ev = moving.events
    t = ev.t.copy()
    t[t >= ev.t[0] + 300_000] += 400_000  # no events for 0.4 s after 0.3 s
    gap = dataclasses.replace(moving, events=EventArray(t, ev.x, ev.y, ev.p))
    cfg = SlamViewConfig(snapshot_every=5)
    whole = SlamEngine(gap, cfg)
    ref = [f.pose for f in iter(whole.step, None)]
    quiet = [k for k, s in enumerate(whole.history) if s.counts["events_in"] == 0]
    assert len(quiet) >= 70
    shared = [k for k in whole._snapshots if k and whole._snapshots[k] is whole._snapshots[k - 5]]
    assert len(shared) >= 10  # in the stretch without events
    e = SlamEngine(gap, cfg)
    first = e.play_step(quiet[0] + 2)
    while e.step_count <= quiet[-1]:
        f = e.play_step(200)
    assert f.index == quiet[-1] + 1 and f.counts["events_in"] > 0  # the stride ends where events come again
    for k in (quiet[0] + 12, quiet[-1] + 3, len(ref) - 1):
        got = whole.seek_step(k).pose
        assert (got is None and ref[k] is None) or np.array_equal(got, ref[k]), k


def _gap_recording(moving, gap_us):
    import dataclasses

    from evpose.core.events import EventArray

    ev = moving.events
    t = ev.t.copy()
    t[t >= ev.t[0] + 300_000] += gap_us  # no events for gap_us after 0.3 s
    return dataclasses.replace(moving, events=EventArray(t, ev.x, ev.y, ev.p))


def _without_timings(history):
    return [(s.index, s.t_us, None if s.pose is None else s.pose.tobytes(), s.status, s.counts) for s in history]


def test_steps_without_events_are_gone_over_at_once_leaving_every_step_as_computing_it_would(moving):
    # SLAM mode computed every empty 5 ms step of an event gap (~0.7 ms each: a 60 s gap took ~8 s to play). After the
    # first empty step SLAM's state and result no longer change, so the rest of the stretch is gone over at once.
    gap = _gap_recording(moving, 2_000_000)  # 400 empty steps
    cfg = SlamViewConfig(snapshot_every=7)
    whole = SlamEngine(gap, cfg)  # every step computed, one at a time (step() never skips)
    ref = [f.pose for f in iter(whole.step, None)]
    quiet = [k for k, s in enumerate(whole.history) if s.counts["events_in"] == 0]
    assert len(quiet) >= 400
    played = SlamEngine(gap, cfg)
    calls = []
    real_step = played.slam.step
    played.slam.step = lambda events: (calls.append(len(events)), real_step(events))[1]
    frames = []
    while (f := played.play_step(50)) is not None:
        frames.append(f)
        if played.step_count >= played.n_steps:
            break
    assert sum(1 for n in calls if n == 0) < 30  # computed: the stretch's first empty step and each stride's shown one
    assert _without_timings(played.history) == _without_timings(whole.history)
    assert quiet[-1] + 1 in [f.index for f in frames]  # the stride still stops where events come again
    assert all(played.history[k].timings_ms == {"step": 0.0} for k in quiet[2:-1] if k not in [f.index for f in frames])
    # The seek snapshots inside the stretch are the state of its steps: seeks restore them and replay exactly.
    assert set(played._snapshots) == set(whole._snapshots)
    for k in (quiet[0] + 40, quiet[-1] - 3, quiet[-1] + 5, len(ref) - 1):
        got = played.seek_step(k).pose
        assert (got is None and ref[k] is None) or np.array_equal(got, ref[k]), k
    # A seek far into the stretch from its start goes over it at once too.
    seeker = SlamEngine(gap, cfg)
    f = seeker.seek_step(quiet[-1] - 1)
    assert _without_timings(seeker.history) == _without_timings(whole.history[:quiet[-1]])
    assert (f.pose is None and ref[quiet[-1] - 1] is None) or np.array_equal(f.pose, ref[quiet[-1] - 1])
