"""Hunt 50c: a recording's very start and end.

Whether a frame shows the person is the majority of the 0.2 s around it
(:func:`features.body.majority`, :func:`cbr.segmentation.sighting_width`); within 0.1 s of
the recording's start or end a frame was read over as many frames on either side as there
were on both, the first and last frame alone, so the person "seen" in the first or last
frames of a stretch with nobody in view stayed seen: "unknown 0-3" before nobody in view
in ``segment``, a sliver of some activity in the last 0.1 s in ``segment`` and ``watch``.
Now such a frame is read over the frames nearest the end, as many as inside: a run at an
end is dropped or kept, by its length, as one inside is.

A clip's joint positions were measured in a frame set over its first tenth whatever it
showed: a window of a recording that starts before the pose model finds the person had
none, and ``segment`` gave the first 0.6-1.7 s unknown; now the frame is set from the first
frame showing the hips. And ``watch`` gave the person's frames before the stream's first
second to a stretch with nobody in view after them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cbr.estimator import CaseBaseClassifier
from cbr.segmentation import NOBODY, segment
from features.poses import PoseSequence
from tests.test_segment import classifier, names, recordings  # noqa: F401 - the fixtures


def test_a_glitch_in_the_first_or_last_frames_of_nobody_in_view_is_no_person(
    recordings: dict[str, PoseSequence],  # noqa: F811 - the fixture imported above
    classifier: CaseBaseClassifier,  # noqa: F811
) -> None:
    """At 30 fps: 2 s with every joint missing (frames 0-60), 13_30's knee raises
    (6.7-11.8 s, every 4th frame of 120 fps: 60-213), 2 s missing (213-273), by
    construction; the person "seen" (copies of the knee raises' first frames) in frames 0-2
    and 270-272, the first and last three: nobody in view exactly 0-60 and 213-273, the knee
    raises between counted 4 (by hand, tests/fixtures/repetition_counts.json), in
    ``segment`` and ``watch`` alike. Before, ``segment`` gave unknown 0-3 and nobody in view
    3-60, and both a sliver of an activity from 270 (jogging in ``segment``, counted 0)."""
    from cbr.live import LiveSegmenter

    rec = recordings["13_30"]
    knee = rec.positions[int(6.7 * 120) : int(11.8 * 120)][::4]
    missing = np.full((60, *knee.shape[1:]), np.nan)
    pos = np.concatenate([missing, knee, missing])
    pos[:3] = knee[:3]
    pos[-3:] = knee[:3]
    rec = PoseSequence(pos, rec.joint_names, 30.0, source="glitches at the ends")
    offline = segment(classifier, rec).segments
    live = LiveSegmenter(classifier, 30.0)
    watched = [s for frame in rec.positions for s in live.push(frame)] + live.finish()
    for got in (offline, watched):
        assert [(s.start_frame, s.end_frame, s.label) for s in got] == [
            (0, 60, None), (60, 213, "KneeRaise"), (213, 273, None)
        ]  # fmt: skip
        assert [s.explanation == NOBODY for s in got] == [True, False, True]
    assert [len(s.repetitions) for s in offline] == [0, 4, 0]
    assert [s.repetitions for s in watched] == [0, 4, 0]


def test_a_clip_that_starts_without_the_person_has_positions_from_where_they_are_seen(
    recordings: dict[str, PoseSequence],  # noqa: F811 - the fixture imported above
) -> None:
    """13_30's twists at 30 fps, 30 frames, after 3 frames with every joint missing: the
    positions of those 30 frames are theirs as a clip alone (both set their frame over 3
    frames, a tenth of 33 or 30 at least 3, from the first showing the hips), and a long
    clip's frame, read in pieces of 8 frames (the first seen in the second), is the same.
    Before, the frame was set over the first 3 frames whatever they showed: every position
    missing, and each window of a recording that starts before the person is seen unlike
    every case."""
    from cbr.long_clip import _position_frame
    from features.body import body_positions, positions_in_frame

    rec = recordings["13_30"]
    twist = rec.positions[int(1.8 * 120) :][::4][:30]
    pos = np.concatenate([np.full((3, *twist.shape[1:]), np.nan), twist])
    late = PoseSequence(pos, rec.joint_names, 30.0, source="late")
    alone = PoseSequence(twist, rec.joint_names, 30.0, source="alone")
    got = body_positions(late)
    assert np.isnan(got[:3]).all()
    np.testing.assert_allclose(got[3:], body_positions(alone), atol=1e-12)
    pieces = positions_in_frame(late.to_canonical().positions, _position_frame(late, 8, False))
    np.testing.assert_allclose(pieces, got, atol=1e-12)


def test_a_recording_that_starts_before_the_person_is_seen_is_segmented_from_its_start(
    recordings: dict[str, PoseSequence],  # noqa: F811 - the fixture imported above
    classifier: CaseBaseClassifier,  # noqa: F811
) -> None:
    """At 30 fps: 0.5 s with every joint missing (the pose model not yet on the person: 15
    frames, under the second a stretch with nobody in view needs), 13_30's twists (1.8-6.7 s:
    15-162), its knee raises (6.7-11.8 s: 162-315): the twists from the start, counted 3, and
    the knee raises 4 (by hand, tests/fixtures/repetition_counts.json). Before, ``segment``
    gave unknown 0-51 (counted 1, a twist) and the twists 51-156 counted 2: the windows
    over the first 0.5 s had no positions (their frame set over frames with nobody), unlike
    every case."""
    rec = recordings["13_30"]
    twist = rec.positions[int(1.8 * 120) : int(6.7 * 120)][::4]
    knee = rec.positions[int(6.7 * 120) : int(11.8 * 120)][::4]
    pos = np.concatenate([np.full((15, *knee.shape[1:]), np.nan), twist, knee])
    got = segment(classifier, PoseSequence(pos, rec.joint_names, 30.0, source="late")).segments
    assert [(s.start_frame, s.label, len(s.repetitions)) for s in got] == [
        (0, "Twist", 3), (got[1].start_frame, "KneeRaise", 4)
    ]  # fmt: skip
    assert abs(got[1].start_frame - 162) <= 9  # the change placed within 0.3 s


def test_the_person_seen_before_the_first_second_and_then_lost_is_not_nobody_in_view(
    recordings: dict[str, PoseSequence],  # noqa: F811 - the fixture imported above
    classifier: CaseBaseClassifier,  # noqa: F811
) -> None:
    """At 30 fps: 13_30's squats' first 0.5 s (frames 0-15), 3 s with every joint missing
    (15-105), its knee raises (6.7-11.8 s: 105-258), by construction: nobody in view exactly
    15-105, the person's frames before it a segment of their own, and the knee raises from
    105 counted 4 (by hand), in ``segment`` and ``watch`` alike. Before, ``watch`` gave
    nobody in view 0-105: its first segment took the label of its first hop, a second in,
    inside the stretch."""
    offline, watched = seen_lost_back(classifier, recordings["13_30"])
    for got in (offline, watched):
        assert [(s.start_frame, s.end_frame) for s in got] == [(0, 15), (15, 105), (105, 258)]
        assert [s.explanation == NOBODY for s in got] == [False, True, False]
        assert got[-1].label == "KneeRaise"
    assert len(offline[-1].repetitions) == watched[-1].repetitions == 4


def seen_lost_back(model: Any, rec: PoseSequence) -> tuple[list[Any], list[Any]]:
    """At 30 fps: ``rec``'s (13_30's) squats' first 0.5 s (frames 0-15), 3 s with every joint
    missing (15-105), its knee raises (6.7-11.8 s: 105-258); its segments by ``segment`` and
    by ``watch``'s live segmenter, of ``model``."""
    from cbr.live import LiveSegmenter

    squat = rec.positions[int(11.8 * 120) : int(12.3 * 120)][::4]
    knee = rec.positions[int(6.7 * 120) : int(11.8 * 120)][::4]
    pos = np.concatenate([squat, np.full((90, *knee.shape[1:]), np.nan), knee])
    rec = PoseSequence(pos, rec.joint_names, 30.0, source="seen, lost, back")
    offline = segment(model, rec).segments
    live = LiveSegmenter(model, 30.0)
    watched = [s for frame in rec.positions for s in live.push(frame)] + live.finish()
    return offline, watched
