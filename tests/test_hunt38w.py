"""Hunt 38w: three or more squats and then one held at the bottom and up again count one
repetition per squat. The squats repeat clearly, so the movement line is read about its
running mean, and a hold longer than the period sags in the middle there: its two ends
stood out as two far points (counted one too many) though, as recorded, the body never came
back up between them (:func:`features.repetitions._one_hold`)."""

from __future__ import annotations

import pytest

from cbr.segmentation import count_in_segment
from features.repetitions import count_repetitions, movement_signals
from tests.test_hunt38b import _squats_then_held
from tests.test_repetitions import FPS

DOWN = 24  # 0.8 s down (and up) at 30 fps
SQUAT = 66  # each squat before the held one: standing 0.6 s, down 0.8 s, up 0.8 s


@pytest.mark.parametrize("squats", [3, 4])
@pytest.mark.parametrize("hold_s", [0.5, 2.0, 6.0, 12.0])
def test_squats_then_one_held_at_the_bottom_count_once_each(squats: int, hold_s: float) -> None:
    """By hand: ``squats`` squats (frames 18 + 66 i down to 42 + 66 i, the bottom, up by
    66 + 66 i, standing 18 frames), then down from frame 18 + 66 ``squats`` to the bottom at
    ``hold`` (24 frames later), held ``hold_s`` seconds, up again over 24 frames and standing
    0.6 s: ``squats`` + 1 repetitions (README "Long recordings": a repetition is a far point
    the movement falls back from on both sides; the held one, come back from, is one). The
    held one runs from the way down (after the squat before it is back up, frame 66
    ``squats``, by frame 18 + 66 ``squats``, where it leaves standing) to where the body is
    back up (within the last 6 frames of the way up) and its far point lies in the hold.
    Before: with holds of 2, 6 and 12 s, ``squats`` + 2 (the hold's two ends); 0.5 s was
    right."""
    seq, hold = _squats_then_held(squats, hold_s, back=True)
    assert hold == 18 + SQUAT * squats + DOWN
    up = hold + int(hold_s * FPS) + DOWN  # back up
    counted = count_repetitions(seq)
    assert counted.count == squats + 1
    for i, r in enumerate(counted.repetitions[:-1]):  # each squat's bottom: frame 42 + 66 i
        assert abs(r.peak_frame - (42 + SQUAT * i)) <= 2
    held = counted.repetitions[-1]
    assert hold <= held.peak_frame < hold + int(hold_s * FPS)
    assert SQUAT * squats <= held.start_frame <= hold - DOWN + 3
    assert up - 6 <= held.end_frame <= up
    assert counted.repetitions[-2].end_frame == held.start_frame  # the spans follow


@pytest.mark.parametrize(("squats", "hold_s"), [(3, 2.0), (4, 12.0)])
def test_a_segment_of_squats_then_one_held_counts_once_each(squats: int, hold_s: float) -> None:
    """The same recording as one segment of ``segment`` and ``watch`` (their rule,
    :func:`cbr.segmentation.count_in_segment`, the recording's own start and end):
    ``squats`` + 1 by hand, as ``reps`` (before: ``squats`` + 2)."""
    seq, _ = _squats_then_held(squats, hold_s, back=True)
    counted = count_in_segment(movement_signals(seq), seq.n_frames, seq.fps, (True, True))
    assert counted.count == squats + 1
