"""Hunt 39f: ``watch`` and ``segment`` count a squat held at the bottom to the end of the
recording alike, across one change of label in the hold or several, however long the hold.

By hand (README, "Long recordings"; tests/fixtures/repetition_counts.json's rule): ``squats``
squats, then down once more and held at the bottom to the end: ``squats`` + 1 repetitions
(the last cut off by the end, its far point in the clip, counted beside whole ones; ``reps``
counts so). The label changing in the hold, the held squat's far point lies on both sides of
the cut; a far point at a segment's end that is a change is left to the segment after, and
one held across a cut is counted by the segment where the body comes back (a hold of 12 s
and up again: ``squats`` and 1 in both, tests/test_hunt38b.py). Ending in the hold, the body
never comes back: the segment that reaches the end counts it, ``squats`` and 1, whether the
stream ended before ``watch`` finished the segment before or after. Before, ``segment``
counted ``squats`` + 1 and 0 (the segment before kept it beside its whole ones), and
``watch`` ``squats`` and 1 when the hold outlasted its delay, ``squats`` + 1 and 0 when the
stream ended first (a hold of 8 s).
"""

from __future__ import annotations

import pytest

from features.repetitions import count_repetitions
from tests.test_hunt36j import _counts
from tests.test_hunt36l import _watched
from tests.test_hunt38b import _both, _squats_then_held
from tests.test_repetitions import FPS


@pytest.mark.parametrize(
    ("squats", "hold_s", "into_hold_s"),
    [(2, 20.0, 0.9), (2, 20.0, 10.0), (2, 8.0, 0.9), (3, 8.0, 0.9), (2, 4.0, 0.9)],
)
def test_a_squat_held_to_the_end_counts_in_the_segment_that_reaches_it(
    squats: int, hold_s: float, into_hold_s: float
) -> None:
    seq, hold = _squats_then_held(squats, hold_s, back=False)
    assert count_repetitions(seq).count == squats + 1
    watched, offline = _both(seq, hold + int(into_hold_s * FPS), 0.0)
    assert watched == offline == [squats, 1]


def test_held_through_two_changes_to_the_end_counts_in_the_last_segment() -> None:
    """Two squats, then held 20 s to the end, the label changing 0.9 s and 6 s into the hold:
    three segments, the middle one all hold: 2, 0 and 1 in both (before: ``segment`` 3, 0
    and 0)."""
    seq, hold = _squats_then_held(2, 20.0, back=False)
    changes = (hold + int(0.9 * FPS), hold + int(6.0 * FPS))
    watched = _watched(seq, changes, pad_s=0.0)
    assert len(watched) == 3
    cuts = [end / FPS for _, end, _ in watched[:-1]]
    assert [r for *_, r in watched] == _counts(seq, cuts) == [2, 0, 1]


def test_a_posture_got_into_and_held_to_the_end_still_counts_none() -> None:
    """Down once and held to the end, nothing before it: a posture got into and held, no
    repetition (``reps`` 0), 0 and 0 in both, as before: the held far point is passed on
    only where the segment before would have counted it."""
    seq, hold = _squats_then_held(0, 8.0, back=False)
    assert count_repetitions(seq).count == 0
    watched, offline = _both(seq, hold + int(0.9 * FPS), 0.0)
    assert watched == offline == [0, 0]
