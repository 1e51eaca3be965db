"""Hunt 48n: "nobody in view" claimed up to 0.7 s of frames where the person is back.

The windows over the edge of a stretch with nobody in view are half empty and come out
unlike every activity; an unknown sliver under :data:`cbr.segmentation.MIN_SEGMENT_S`
beside the stretch joined it, in ``segment`` and in ``watch``: a video with 5 s of black,
then a person, was "nobody in view" 0.00-5.72 s. Now a segment with nobody in view holds
only frames without the person: an unknown sliver under a second after it joins the
activity that follows (the activity starts where the person is seen again), one between two
such stretches joins them (the person seen for a flicker), any other stays unknown.
"""

from __future__ import annotations

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.segmentation import NOBODY, segment
from features.poses import PoseSequence
from tests.test_segment import classifier, names, recordings  # noqa: F401 - the fixtures


def _away_and_back(rec: PoseSequence, flicker: bool) -> PoseSequence:
    """At 30 fps (13_30 at 120 fps, every 4th frame): 3 s with every joint missing (frames
    0-90), 13_30's knee raises (6.7-11.8 s, 153 frames: 90-243), 2 s missing (243-303),
    its squats (11.8-16.1 s: 303-432); ``flicker``: the person seen in 2 frames (45, 46)
    in the middle of the first stretch, as a pose model's glitch."""
    knee = rec.positions[int(6.7 * 120) : int(11.8 * 120)][::4]
    squat = rec.positions[int(11.8 * 120) : int(16.1 * 120)][::4]
    missing = np.full((90, *knee.shape[1:]), np.nan)
    pos = np.concatenate([missing, knee, missing[:60], squat])
    if flicker:
        pos[45:47] = knee[:2]
    return PoseSequence(pos, rec.joint_names, 30.0, source="away")


EXPECTED = [(0, 90, None), (90, 243, "KneeRaise"), (243, 303, None), (303, 432, "Squat")]


@pytest.mark.parametrize("flicker", [False, True])
def test_nobody_in_view_ends_where_the_person_is_seen_again(
    recordings: dict[str, PoseSequence],  # noqa: F811 - the fixture imported above
    classifier: CaseBaseClassifier,  # noqa: F811
    flicker: bool,
) -> None:
    """The recording above: nobody in view exactly 0-90 and 243-303 (by construction), the
    knee raises from frame 90 and counted 4, the squats 2 (as 13_30's by hand,
    tests/test_segment.py), in ``segment`` and ``watch`` alike; a flicker of the person
    inside the first stretch does not split it. Before, ``segment`` gave nobody in view
    0-111 and ``watch`` 0-105: the knee raises' first half-empty windows, unknown, joined it."""
    assert_as_expected(classifier, _away_and_back(recordings["13_30"], flicker))


def assert_as_expected(clf: CaseBaseClassifier, rec: PoseSequence) -> None:
    """``segment`` and ``watch``'s segmenter give ``rec`` the segments of :data:`EXPECTED`,
    nobody in view where it says None, the knee raises counted 4 and the squats 2."""
    from cbr.live import LiveSegmenter

    offline = segment(clf, rec).segments
    live = LiveSegmenter(clf, 30.0)
    watched = [s for frame in rec.positions for s in live.push(frame)] + live.finish()
    for got in (offline, watched):
        assert [(s.start_frame, s.end_frame, s.label) for s in got] == EXPECTED
        assert [s.explanation == NOBODY for s in got] == [True, False, True, False]
    assert [len(s.repetitions) for s in offline] == [0, 4, 0, 2]
    assert [s.repetitions for s in watched] == [0, 4, 0, 2]


def test_the_rule_for_slivers_beside_nobody() -> None:
    """Decoded paths by hand (0.1-s blocks; activities 0 and 1, 2 unknown, 3 nobody): a
    sliver of unknown under a second after nobody joins the activity after it; between two
    stretches of nobody, nobody; before nobody, at the end, or a second or longer, it stays
    unknown."""
    from cbr.segmentation import _slivers_beside_nobody

    def given(path: list[int]) -> list[int]:
        return _slivers_beside_nobody(np.array(path), 2).tolist()

    assert given([3] * 10 + [2] * 7 + [0] * 10) == [3] * 10 + [0] * 17
    assert given([3] * 10 + [2] * 2 + [3] * 10) == [3] * 22
    assert given([0] * 10 + [2] * 7 + [3] * 10) == [0] * 10 + [2] * 7 + [3] * 10
    assert given([3] * 10 + [2] * 7) == [3] * 10 + [2] * 7
    assert given([3] * 10 + [2] * 10 + [1] * 10) == [3] * 10 + [2] * 10 + [1] * 10
