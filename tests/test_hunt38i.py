"""Hunt 38i: ``watch`` (the live segmenter) counts each segment as ``segment`` counts it,
reading past a period of noise (hunt 38c, :func:`cbr.segmentation.count_in_segment`): the
bundled side-lying leg raises cut where ``segment`` cuts them count 2 in ``watch`` too."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from features.poses import PoseSequence
from features.repetitions import count_repetitions
from tests.test_hunt36i import _hand, _segment_counts, _video
from tests.test_hunt36l import _live_segments
from tests.test_hunt38b import _squats_then_held
from tests.test_repetitions import FPS

LEG_RAISE = "side_lying_leg_raise/fit_lateral_leg_raise_pexels6974513.mp4"
CUT = 43  # frame 43, 1.72 s: where segment with the README's workout case base cuts it


def _streamed(seq: PoseSequence, change: int) -> list[tuple[int, int, int]]:
    """(start_frame, end_frame, repetitions) of each segment ``watch`` gives ``seq``, pushed
    frame by frame with its joints' confidence as ``watch`` pushes a video's, the label
    changing at frame ``change``."""
    assert seq.confidence is not None
    out = _live_segments(seq.positions, seq.fps, (change,), seq.confidence)
    return [(s.start_frame, s.end_frame, s.repetitions) for s in out]


def test_watch_counts_the_leg_raise_segment_as_segment_does(
    bundled_poses: Callable[[str], PoseSequence],
) -> None:
    """The bundled side-lying leg raises (leg up 2.2-4.8 s and from 8.4 s to the end, watched:
    2 by hand), streamed through ``watch`` with the label changing at 1.72 s (where
    ``segment`` with the README's workout case base cuts them); ``watch`` places the change
    at 1.60 s (frame 40). Its segments count 0 and 2, as ``segment`` cut where ``watch`` cut
    counts them. Before: 0 and 1, the segment after the cut read along the arm under the
    head (a period of noise gave the raised leg no weight), where ``segment`` reads past it."""
    seq = _video(bundled_poses, LEG_RAISE)
    hand = _hand(LEG_RAISE)["count"]
    watched = _streamed(seq, CUT)
    assert len(watched) == 2
    (a, cut, first), (cut_too, end, second) = watched
    assert a == 0 and cut == cut_too == 40 and end == seq.n_frames
    assert _segment_counts(seq, [cut / seq.fps]) == [first, second] == [0, hand] == [0, 2]


@pytest.mark.parametrize(("squats", "hold_s"), [(1, 6.0), (2, 12.0), (2, 20.0)])
def test_a_squat_held_long_at_the_bottom_and_up_again_counts(squats: int, hold_s: float) -> None:
    """``squats`` squats (0.6 s standing, down 0.8 s, up 0.8 s, each 2.2 s), then down once
    more, held at the bottom ``hold_s`` seconds and up again, standing 0.6 s: by hand
    ``squats`` + 1 (README: a repetition is a far point the movement falls back from on both
    sides; one held, then come back from, is one, as the bundled slow reverse lunge, down,
    held low and up again). The held squat runs from the way down to where the body is
    back up: down from frame 18 + 66 x ``squats``, up by 24 frames after its hold. Before:
    ``squats``, the hold, longer than two of the squats' 2.2-s periods, measured from its own
    level and taken for a still stretch at rest."""
    seq, hold = _squats_then_held(squats, hold_s, back=True)
    end = hold + int(hold_s * FPS) + 24  # back up
    counted = count_repetitions(seq)
    assert counted.count == squats + 1
    last = counted.repetitions[-1]
    assert hold <= last.peak_frame < hold + int(hold_s * FPS)
    assert last.start_frame <= hold - 24 + 3 and end - 6 <= last.end_frame <= end
    for i, r in enumerate(counted.repetitions[:-1]):  # each squat's bottom: frame 42 + 66 i
        assert abs(r.peak_frame - (42 + 66 * i)) <= 2
