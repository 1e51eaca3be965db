"""Hunt 41r: a repetition cut off at the recording's start or end counts in a segment as the
whole recording counts it, wherever the cut before (or after) it falls: judged beside the
repetitions of the segment across the cut (:func:`cbr.segmentation._beside_whole`); a posture
got into in one segment and held to the end in the last counts none there
(:func:`cbr.segmentation._held_into_the_end`)."""

from __future__ import annotations

import numpy as np
import pytest

from features.poses import PoseSequence
from features.repetitions import count_repetitions
from tests.bodies import standing, to_sequence
from tests.test_hunt36j import _counts
from tests.test_hunt36l import _watched
from tests.test_hunt38b import _squats_then_held
from tests.test_repetitions import FPS, _raise_arms

DOWN = 24  # 0.8 s down (and up) at 30 fps
REST = 18  # 0.6 s standing before each squat


def _reversed(seq: PoseSequence) -> PoseSequence:
    return PoseSequence(seq.positions[::-1].copy(), seq.joint_names, seq.fps)


@pytest.mark.parametrize(("squats", "hold_s"), [(2, 0.3), (3, 0.5)])
@pytest.mark.parametrize("before_s", [0.1, 0.3, 0.5])
def test_the_last_squat_cut_off_by_the_end_counts_after_a_cut_at_rest(
    squats: int, hold_s: float, before_s: float
) -> None:
    """By construction: ``squats`` squats (knees 180 -> 50 -> 180 degrees), standing 0.6 s,
    then down the whole way once more and the recording ends ``hold_s`` s later at the
    bottom: ``squats`` whole repetitions and one cut off by the end as deep as they are,
    which ``reps`` counts beside them (README, "a far point cut off by the end counts beside
    whole ones"): ``squats`` + 1. Cut in the standing before that last way down (``before_s``
    before it starts), the segments count ``squats`` and 1. Before: ``squats`` and 0, the
    segment after the cut holding no whole repetition to measure it against."""
    seq, hold = _squats_then_held(squats, hold_s, back=False)
    assert count_repetitions(seq).count == squats + 1
    cut = hold - DOWN - int(round(before_s * FPS))
    assert hold - DOWN - REST < cut < hold - DOWN  # in the standing
    assert _counts(seq, [cut / FPS]) == [squats, 1]


@pytest.mark.parametrize("after_s", [0.1, 0.3, 0.5])
def test_the_first_squat_cut_off_by_the_start_counts_before_a_cut_at_rest(after_s: float) -> None:
    """The same recording played backwards (two squats and the way down, 0.5 s at the
    bottom): it starts at the bottom 0.5 s, rises the whole way and stands 0.6 s, then
    squats twice; ``reps`` counts 3. Cut in the standing after the first rise (``after_s``
    after it ends): 1 and 2. Before: 0 and 2."""
    seq, _ = _squats_then_held(2, 0.5, back=False)
    back = _reversed(seq)
    assert count_repetitions(back).count == 3
    up = int(0.5 * FPS) + DOWN  # the first rise ends here
    cut = up + int(round(after_s * FPS))
    assert up < cut < up + REST
    assert _counts(back, [cut / FPS]) == [1, 2]


def test_a_posture_got_into_and_held_after_a_cut_stays_none() -> None:
    """Two squats, then down once more and held 20 s to the end, cut 0.9 s into the hold:
    2 and 1 (tests/test_hunt38b.py), unchanged: the segment after the cut had the held
    squat already (a far point held across the cut, :func:`cbr.segmentation._held_across`)."""
    seq, hold = _squats_then_held(2, 20.0, back=False)
    assert _counts(seq, [(hold + int(0.9 * FPS)) / FPS]) == [2, 1]


def _arms_raised_sagging() -> PoseSequence:
    """Standing 0.6 s, both arms raised sideways to 90 degrees over 0.8 s (eased), held 0.5 s,
    sinking steadily to 70 degrees over 3 s, then held still 1.5 s to the end (6.4 s)."""
    rest, move = int(0.6 * FPS), int(0.8 * FPS)
    up = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, move)))
    sag = 90.0 - 20.0 * np.linspace(0.0, 1.0, int(3.0 * FPS))
    degrees = np.concatenate(
        [
            np.zeros(rest),
            90.0 * up,
            np.full(int(0.5 * FPS), 90.0),
            sag,
            np.full(int(1.5 * FPS), 70.0),
        ]
    )
    body = standing()
    return to_sequence(*(_raise_arms(body, a, a) for a in degrees), fps=FPS)


@pytest.mark.parametrize("cut_s", [1.6, 2.0, 2.5, 3.0])
def test_a_posture_got_into_and_held_sagging_counts_none_cut_in_its_hold(cut_s: float) -> None:
    """By construction the arms go up once and never come back down: a posture got into and
    held (the 20-degree sag comes during the hold, which ends still), no repetition;
    ``reps`` counts 0. Cut in the hold (0.2 to 1.6 s after the arms are up, before the sag
    ends), the segments count 0 and 0. Before: 0 and 1, the way up handed across the cut to
    the segment after, whose line falls 20 degrees from it (the bundled side plank, its
    shoulder sinking 16 degrees, cut in its hold: 1 at 135 of 195 cuts)."""
    seq = _arms_raised_sagging()
    assert count_repetitions(seq).count == 0
    assert _counts(seq, [cut_s]) == [0, 0]


@pytest.mark.parametrize("cut_s", [1.6, 2.5])
def test_watch_counts_the_posture_got_into_and_held_none_as_segment(cut_s: float) -> None:
    """The same arms, streamed to ``watch`` with the label changing at ``cut_s``: two
    segments, 0 and 0, as ``segment`` counts them (:meth:`cbr.live.LiveSegmenter._got_into`).
    Before: 0 and 1, the way up held on past the first segment's end and counted by the
    last, whose line falls 20 degrees from it."""
    watched = _watched(_arms_raised_sagging(), (int(cut_s * FPS),), pad_s=0.0)
    assert len(watched) == 2
    assert 42 < watched[0][1] < 147  # cut in the hold: arms up at 1.4 s, the sag ends at 4.9 s
    assert [r for *_, r in watched] == [0, 0]
