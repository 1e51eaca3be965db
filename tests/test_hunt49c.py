"""Hunt 49c: a glitch of the pose model near the edge of a stretch with nobody in view moved
the edge.

A stretch with nobody in view is one of at least :data:`cbr.segmentation.MIN_SEGMENT_S`
without the person; the pose model "seeing" a person for a frame or two inside it (a false
detection) cut it in two, and the piece under a second beside the glitch was no stretch
with nobody in view: 3 s with nobody, a glitch at frame 10, was unknown 0-12 and nobody in
view 12-90 in ``segment``; a glitch 10 frames before the person came back started the
activity there in ``watch``. Now whether a frame shows the person is the majority of the
frames within the running median of the movement signals around it (0.2 s; at 30 fps 7
frames: a run of up to 3 frames dropped), in both. And a sliver of an activity under a
second after such a stretch (the decoder's run from before it, cut short) joins what
follows, as an unknown one does: the activity starts where the person is seen again.
"""

from __future__ import annotations

import numpy as np

from cbr.estimator import CaseBaseClassifier
from cbr.segmentation import NOBODY, segment
from features.body import majority
from features.poses import PoseSequence
from tests.test_hunt48n import _away_and_back, assert_as_expected
from tests.test_segment import classifier, names, recordings  # noqa: F401 - the fixtures


def test_majority_by_hand() -> None:
    """Runs shorter than half the width go, longer ones keep their edges; near the ends a
    sample is read over the ``width`` samples nearest the end, so a short run there goes
    as one inside does (hunt 50c: the two leading 1s, under half of 5, go; before, the first
    sample was read alone and the second over three)."""
    got = majority(np.array([1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 0, 1, 1], bool), 5)
    assert got.tolist() == [bool(x) for x in [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1]]
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
    rec = _away_and_back(recordings["13_30"], flicker=False)
    pos = rec.positions.copy()
    for first in (10, 80, 250, 290):
        pos[first : first + 2] = pos[90:92]
    pos[150:152] = np.nan
    assert_as_expected(classifier, PoseSequence(pos, rec.joint_names, 30.0, source="glitches"))


def test_a_sliver_of_an_activity_after_nobody_in_view_joins_what_follows() -> None:
    """Decoded paths by hand (0.1-s blocks; activities 0 and 1, 2 unknown, 3 nobody): a run
    of an activity under a second after nobody joins what follows it, as an unknown one
    does; between two stretches of nobody, before nobody, or at the end, it stays."""
    from cbr.segmentation import _slivers_beside_nobody

    def given(path: list[int]) -> list[int]:
        return _slivers_beside_nobody(np.array(path), 2).tolist()

    assert given([3] * 10 + [0] * 2 + [1] * 10) == [3] * 10 + [1] * 12
    assert given([3] * 10 + [0] * 9 + [2] * 10) == [3] * 10 + [2] * 19
    assert given([3] * 10 + [0] * 2 + [3] * 10) == [3] * 10 + [0] * 2 + [3] * 10
    assert given([1] * 10 + [0] * 2 + [3] * 10) == [1] * 10 + [0] * 2 + [3] * 10
    assert given([3] * 10 + [0] * 2) == [3] * 10 + [0] * 2
    assert given([3] * 10 + [0] * 10 + [1] * 10) == [3] * 10 + [0] * 10 + [1] * 10


def test_the_activity_after_nobody_in_view_starts_where_the_person_is_seen_again(
    recordings: dict[str, PoseSequence],  # noqa: F811 - the fixture imported above
    classifier: CaseBaseClassifier,  # noqa: F811
) -> None:
    """At 30 fps: 13_30's squats (11.8-16.1 s: frames 0-129), its knee raises (6.7-9.7 s:
    129-219), the person held still (the knee raises' 90th frame, 219-255), lost for 3 s
    (255-345), its squats again (345-474): nobody in view exactly 255-345 and the squats
    from 345, counted 2 as by hand (tests/test_segment.py), in ``segment`` and ``watch``
    alike. Before, ``segment`` gave 345-351 to the knee raises (the run the decoder found
    before the stretch, cut short by it)."""
    from cbr.live import LiveSegmenter

    rec = recordings["13_30"]
    knee = rec.positions[int(6.7 * 120) : int(11.8 * 120)][::4]
    squat = rec.positions[int(11.8 * 120) : int(16.1 * 120)][::4]
    still = np.repeat(knee[89:90], 36, axis=0)
    missing = np.full((90, *knee.shape[1:]), np.nan)
    pos = np.concatenate([squat, knee[:90], still, missing, squat])
    rec = PoseSequence(pos, rec.joint_names, 30.0, source="still, away and back")
    offline = segment(classifier, rec).segments
    live = LiveSegmenter(classifier, 30.0)
    watched = [s for frame in rec.positions for s in live.push(frame)] + live.finish()
    for got in (offline, watched):
        assert [(s.start_frame, s.end_frame, s.label) for s in got[-2:]] == [
            (255, 345, None), (345, 474, "Squat")
        ]  # fmt: skip
        assert got[-2].explanation == NOBODY
    assert len(offline[-1].repetitions) == watched[-1].repetitions == 2
