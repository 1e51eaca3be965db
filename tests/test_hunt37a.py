"""Hunt 37a: ``segment`` counted 1 side-lying leg raise where ``reps`` and the hand count
(tests/fixtures/repetition_counts.json) say 2."""

from __future__ import annotations

from pathlib import Path

from features.repetitions import count_in_signals, movement_signals
from tests.test_hunt36i import _hand, _segment_counts, _video

LEG_RAISE = "side_lying_leg_raise/fit_lateral_leg_raise_pexels6974513.mp4"
SIDE_PLANK = "side_plank/fit_side_plank_pexels6023266.mp4"


def test_the_leg_raise_segment_counts_both_raises(shared_data: Path) -> None:
    """The bundled side-lying leg raises (leg up 2.2-4.8 s and from 8.4 s to the end: 2 by
    hand), cut where ``segment`` with the README's workout case base cut them (1.72 s, the
    first 1.72 s unknown): the segment after the cut counts both raises, as ``reps`` on the
    whole clip does. Before: 1, read along the arm under the head, whose weight came from a
    period of noise (1.76 s, autocorrelation 0.006) that gave the raised leg none."""
    seq = _video(shared_data, LEG_RAISE)
    hand = _hand(LEG_RAISE)["count"]
    assert _segment_counts(seq, []) == [hand] == [2]
    assert _segment_counts(seq, [1.72]) == [0, hand]


def test_the_leg_raise_segment_is_read_along_the_raised_leg(shared_data: Path) -> None:
    """The segment's movement direction: the left hip (the raised leg, 50 degrees) carries
    the most of it, where before it carried none (the right armpit and elbow, the arm under
    the head, all)."""
    seq = _video(shared_data, LEG_RAISE)
    sig = movement_signals(seq)
    found = count_in_signals(
        sig.part(43, len(sig.values)), seq.n_frames - 43, seq.fps, (False, True)
    )
    assert found.moving[0] == "left_hip", found.moving
    assert len(found.repetitions) == 2


def test_the_side_plank_keeps_no_repetition_where_segment_cuts_it(shared_data: Path) -> None:
    """The side plank (0 by hand), cut at 6.20 s (where ``segment`` cuts it) and at 5.72 s
    (where it cut it when a period of noise weighed nothing at all, the rule tried before
    this one: 1 and 1 there): 0 and 0 in both, as the whole clip."""
    seq = _video(shared_data, SIDE_PLANK)
    hand = _hand(SIDE_PLANK)["count"]
    assert _segment_counts(seq, []) == [hand] == [0]
    for cut_s in (6.2, 5.72):
        assert _segment_counts(seq, [cut_s]) == [0, 0], cut_s
