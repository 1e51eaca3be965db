"""Hunt 49c: a glitch of the pose model near the edge of a stretch with nobody in view moved
the edge.

A stretch with nobody in view is one of at least :data:`cbr.segmentation.MIN_SEGMENT_S`
without the person; the pose model "seeing" a person for a frame or two inside it (a false
detection) cut it in two, and the piece under a second beside the glitch was no stretch
with nobody in view: 3 s with nobody, a glitch at frame 10, was unknown 0-12 and nobody in
view 12-90 in ``segment``; a glitch 10 frames before the person came back started the
activity there in ``watch``. Now whether a frame shows the person is the majority of the
frames within the running median of the movement signals around it (0.2 s; at 30 fps 7
frames: a run of up to 3 frames dropped), in both.
"""

from __future__ import annotations

import numpy as np

from cbr.estimator import CaseBaseClassifier
from cbr.segmentation import NOBODY, segment
from features.body import majority
from features.poses import PoseSequence
from tests.test_hunt48n import EXPECTED, _away_and_back
from tests.test_segment import classifier, names, recordings  # noqa: F401 - the fixtures


def test_majority_by_hand() -> None:
    """Runs shorter than half the width go, longer ones keep their edges; near the ends the
    window holds as many samples on either side as there are on both (the first and last
    sample as they are)."""
    got = majority(np.array([1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 0, 1, 1], bool), 5)
    assert got.tolist() == [bool(x) for x in [1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1]]
    assert majority(np.array([1, 0, 1, 0, 1, 0], bool), 3).tolist() == [
        True, True, False, True, False, False
    ]  # fmt: skip


def test_a_glitch_near_an_edge_of_nobody_in_view_does_not_move_it(
    recordings: dict[str, PoseSequence],  # noqa: F811 - the fixture imported above
    classifier: CaseBaseClassifier,  # noqa: F811
) -> None:
    """tests/test_hunt48n.py's recording (at 30 fps: nobody in view 0-90, 13_30's knee
    raises 90-243, nobody 243-303, its squats 303-432, by construction) with the person
    "seen" for two frames (copies of the knee raises' first) at frames 10, 80, 250 and 290,
    each within a second of an edge of the stretch it lies in, and two frames of the knee
    raises missed (150, 151): the segments as without them, nobody in view exactly 0-90 and
    243-303, counted 4 and 2 (as by hand, tests/test_segment.py), in ``segment`` and
    ``watch`` alike. Before, ``segment`` gave 0-12 unknown, 81-111 unknown and the knee
    raises 111-246, and ``watch`` the knee raises from 80 and the squats from 290."""
    from cbr.live import LiveSegmenter

    rec = _away_and_back(recordings["13_30"], flicker=False)
    pos = rec.positions.copy()
    for first in (10, 80, 250, 290):
        pos[first : first + 2] = pos[90:92]
    pos[150:152] = np.nan
    rec = PoseSequence(pos, rec.joint_names, 30.0, source="glitches")
    offline = segment(classifier, rec).segments
    live = LiveSegmenter(classifier, 30.0)
    watched = [s for frame in rec.positions for s in live.push(frame)] + live.finish()
    for got in (offline, watched):
        assert [(s.start_frame, s.end_frame, s.label) for s in got] == EXPECTED
        assert [s.explanation == NOBODY for s in got] == [True, False, True, False]
    assert [len(s.repetitions) for s in offline] == [0, 4, 0, 2]
    assert [s.repetitions for s in watched] == [0, 4, 0, 2]
