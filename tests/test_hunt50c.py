"""Hunt 50c: a glitch of the pose model within 0.1 s of a recording's start or end.

Whether a frame shows the person is the majority of the 0.2 s around it
(:func:`features.body.majority`, :func:`cbr.segmentation.sighting_width`); within 0.1 s of
the recording's start or end a frame was read over as many frames on either side as there
were on both, the first and last frame alone, so the person "seen" in the first or last
frames of a stretch with nobody in view stayed seen: "unknown 0-3" before nobody in view
in ``segment``, a sliver of some activity in the last 0.1 s in ``segment`` and ``watch``.
Now such a frame is read over the frames nearest the end, as many as inside: a run at an
end is dropped or kept, by its length, as one inside is.
"""

from __future__ import annotations

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
