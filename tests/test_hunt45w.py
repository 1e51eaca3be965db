"""Hunt 45w: ``watch`` counts each segment as ``segment`` counts it, cut where ``watch`` cut:
on the movement signals of the frames either side of the segment too
(:meth:`cbr.live.LiveSegmenter._in_context`, as ``segment`` reads the whole recording's), a
far point at a cut that the segment across it does not take kept where the movement turns
within the segment (:func:`cbr.segmentation.unclaimed`, the same function), and a segment
after one with no far point at all counted with its start settled. The bundled videos' poses
(BlazePose, as ``extract`` reads them) streamed with a scripted label change; the hand counts
are tests/fixtures/repetition_counts.json's."""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace

import pytest

from features.poses import PoseSequence
from tests.test_hunt36j import _counts
from tests.test_hunt36l import LABELS, _Changing


def _streamed(seq: PoseSequence, change_s: float) -> list[tuple[int, int, int]]:
    """(start, end, repetitions) of each segment ``watch``'s live segmenter gives ``seq``
    pushed frame by frame with its joints' confidence, the label changing ``change_s`` s in,
    the stream ending with the last frame."""
    clf = SimpleNamespace(classes_=LABELS, case_base_=SimpleNamespace(labels=LABELS))
    live = _Changing(clf, seq.fps, judge=SimpleNamespace())
    live.changes = (int(change_s * seq.fps),)
    assert seq.confidence is not None
    out = []
    for frame, seen in zip(seq.positions, seq.confidence, strict=True):
        out += live.push(frame, seen)
    out += live.finish()
    return [(s.start_frame, s.end_frame, s.repetitions) for s in out]


def _both(seq: PoseSequence, change_s: float) -> tuple[list[int], list[int]]:
    """Each segment's count by ``watch`` and by ``segment`` cut where ``watch`` cut."""
    watched = _streamed(seq, change_s)
    offline = _counts(seq, [end / seq.fps for _, end, _ in watched[:-1]])
    return [r for *_, r in watched], offline


@pytest.fixture(scope="module")
def bridge(bundled_poses: Callable[[str], PoseSequence]) -> PoseSequence:
    """The bundled glute bridge video's poses (167 frames at 25 fps)."""
    return bundled_poses("glute_bridge/fit_glute_bridge_pexels6525487.mp4").to_canonical()


@pytest.fixture(scope="module")
def plank(bundled_poses: Callable[[str], PoseSequence]) -> PoseSequence:
    """The bundled side plank video's poses (215 frames at 25 fps)."""
    return bundled_poses("side_plank/fit_side_plank_pexels6023266.mp4").to_canonical()


def test_watch_keeps_a_far_point_the_segment_after_the_cut_does_not_take(
    bridge: PoseSequence,
) -> None:
    """Three bridges by hand (hips up at 0.0-1.1 s, 2.8-3.9 s and 5.9-6.6 s). The label
    changing 1.5 s in, ``watch`` cuts at 1.12 s; ``segment`` cut there counts 0 and 3, the
    hand's 3 in all: the second segment keeps a far point at its start that the first
    segment has none at, the movement turning within it
    (:func:`cbr.segmentation.unclaimed`). Before, ``watch`` did not ask and counted 0 and
    2, the far point in neither (checked: fails on the old code)."""
    assert bridge.fps == 25.0
    watched, offline = _both(bridge, 1.5)
    assert watched == offline == [0, 3]


@pytest.mark.parametrize(("start", "change_s"), [(30, 2.5), (70, 3.5)])
def test_watch_counts_a_segment_on_the_frames_either_side_as_segment(
    lunge_poses: PoseSequence, start: int, change_s: float
) -> None:
    """One slow lunge by hand, lowest 1.5-3.6 s, lowering again at the end, not yet down.
    Streamed from 1.2 s (frame 30) or from 2.8 s (frame 70, in the lowest stretch), the
    label changing 2.5 or 3.5 s in (both after the lunge's lowest): 1 and 0 by hand, and by
    ``segment`` cut where ``watch`` cut. ``watch`` now counts each segment on the signals of
    the frames either side of it too, as ``segment`` counts on the whole recording's
    (:meth:`cbr.live.LiveSegmenter._in_context`). Before, on the segment's frames alone,
    smoothed up to its ends: 2 and 1, and 2 and 0 (checked: fails on the old code)."""
    seq = lunge_poses.to_canonical()
    assert seq.fps == 25.0
    watched, offline = _both(seq.slice_frames(start, seq.n_frames), change_s)
    assert watched == offline == [1, 0]


@pytest.mark.parametrize("start", [25, 30])
def test_watch_settles_the_start_of_a_segment_after_one_with_no_far_point(
    plank: PoseSequence, start: int
) -> None:
    """The side plank: no repetition by hand (got into once and held). Streamed from frame
    25 or 30, the label changing 1.5 s in, before the way into the plank: the first segment
    has no far point at all, so the second's start is settled (nothing turns at that cut)
    and the way into the plank, held to the end, is no repetition: 0 and 0, as ``segment``
    counts it. Before, ``watch`` counted 0 and 1 from frame 30 (frame 25: 0 and 0 before,
    0 and 1 with the segments counted on the frames either side but the start not settled;
    checked)."""
    assert plank.fps == 25.0
    watched, offline = _both(plank.slice_frames(start, plank.n_frames), 1.5)
    assert watched == offline == [0, 0]


def test_the_last_segment_is_judged_beside_a_whole_repetition_only(
    bundled_poses: Callable[[str], PoseSequence],
) -> None:
    """The bundled two people's chair squats streamed to frame 180 (7.5 s at 24 fps), the
    label changing 2.5 s before the end: ``watch`` cuts at frame 108, and ``segment`` cut
    there counts 1 and 1. The first segment holds no far point of its own (the one it counts
    is cut off by the start, judged beside the segment after), so the last segment's far
    point cut off by the end has no repetition of the segment before to be judged beside,
    as ``segment`` judges it (:func:`cbr.segmentation._beside_whole`: the segment across
    the cut's own repetitions). Before, ``watch`` judged it beside the first segment's
    cut-off far point and counted 1 and 2 (checked: fails on the old code)."""
    seq = bundled_poses("edge/chair_squat_two_people_pexels4838146.mp4").to_canonical()
    assert seq.fps == 24.0
    watched, offline = _both(seq.slice_frames(0, 180), 180 / 24.0 - 2.5)
    assert watched == offline == [1, 1]
