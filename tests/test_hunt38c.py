"""Hunt 38c: ``segment`` counted 1 side-lying leg raise where ``reps`` and the hand count
(tests/fixtures/repetition_counts.json) say 2. The rule that fixes it (a period of noise does
not weigh out the angle that moves most) is a segment's count's only: tried on every count
(hunt 37a) it moved the windows ``segment`` classifies, and CMU 13_31 lost its second Twist
(tests/test_readme_mocap.py)."""

from __future__ import annotations

from collections.abc import Callable

from cbr.segmentation import counted_segments
from features.poses import PoseSequence
from features.repetitions import count_in_signals, count_repetitions, movement_signals
from tests.test_hunt36i import _hand, _segment_counts, _video

LEG_RAISE = "side_lying_leg_raise/fit_lateral_leg_raise_pexels6974513.mp4"
SIDE_PLANK = "side_plank/fit_side_plank_pexels6023266.mp4"
CUT = 43  # frame 43, 1.72 s: where segment with the README's workout case base cuts it


def test_the_leg_raise_segment_counts_both_raises(
    bundled_poses: Callable[[str], PoseSequence],
) -> None:
    """The bundled side-lying leg raises (leg up 2.2-4.8 s and from 8.4 s to the end, watched:
    2 by hand), cut where ``segment`` with the README's workout case base cut them (1.72 s,
    the first 1.72 s unknown): the segment after the cut counts both raises, as ``reps`` on
    the whole clip does, each far point in one raise. Before: 1, read along the arm under
    the head, whose weight came from a period of noise (1.76 s, autocorrelation 0.006) that
    gave the raised leg none."""
    seq = _video(bundled_poses, LEG_RAISE)
    hand = _hand(LEG_RAISE)["count"]
    assert _segment_counts(seq, []) == [hand] == [2]
    assert _segment_counts(seq, [CUT / seq.fps]) == [0, hand]
    bounds = [(0, CUT), (CUT, seq.n_frames)]
    _, after = counted_segments(movement_signals(seq), bounds, seq.n_frames)
    peaks = [r.peak_frame / seq.fps for r in after]
    assert 2.2 <= peaks[0] <= 4.8 and 8.4 <= peaks[1] <= 10.0, peaks
    assert count_repetitions(seq).count == hand


def test_the_leg_raise_segment_is_read_along_the_raised_leg(
    bundled_poses: Callable[[str], PoseSequence],
) -> None:
    """The segment's movement direction, counted as ``segment`` counts (``past_noise``): the
    left hip (the raised leg) carries the most of it, where before the right armpit and elbow
    (the arm under the head) carried it all. Without ``past_noise`` (the windows ``segment``
    classifies, ``reps``) the stretch is read as before: the rule is the count's only."""
    seq = _video(bundled_poses, LEG_RAISE)
    sig = movement_signals(seq)
    part = sig.part(CUT, len(sig.values))
    counted = count_in_signals(part, seq.n_frames - CUT, seq.fps, (False, True), past_noise=True)
    assert counted.moving[0] == "left_hip", counted.moving
    assert len(counted.repetitions) == 2
    as_before = count_in_signals(part, seq.n_frames - CUT, seq.fps, (False, True))
    assert "left_hip" not in as_before.moving, as_before.moving
    assert len(as_before.repetitions) == 1


def test_the_side_plank_keeps_no_repetition_where_segment_cuts_it(
    bundled_poses: Callable[[str], PoseSequence],
) -> None:
    """The side plank (0 by hand), cut at 6.20 s (where ``segment`` cuts it) and at 5.72 s
    (where it cut it when a period of noise weighed nothing at all, the rule tried in hunt
    36: 1 and 1 there): 0 and 0 in both, as the whole clip."""
    seq = _video(bundled_poses, SIDE_PLANK)
    hand = _hand(SIDE_PLANK)["count"]
    assert _segment_counts(seq, []) == [hand] == [0]
    for cut_s in (6.2, 5.72):
        assert _segment_counts(seq, [cut_s]) == [0, 0], cut_s
