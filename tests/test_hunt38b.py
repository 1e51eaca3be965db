"""Hunt 38b: ``watch`` (the live segmenter) and ``segment`` count the end of a stream alike: a
squat that goes down and is held at the bottom, through a change of label, until the
recording ends (or for longer than ``watch`` waits before finishing the segment before the
change)."""

from __future__ import annotations

import numpy as np
import pytest

from features.poses import PoseSequence
from features.repetitions import count_repetitions
from tests.bodies import squat_pose, to_sequence
from tests.test_hunt36j import MOVE_S, REST_S, _counts, _eased
from tests.test_hunt36l import _watched
from tests.test_repetitions import FPS


def _squats_then_held(squats: int, hold_s: float, back: bool) -> tuple[PoseSequence, int]:
    """Standing 0.6 s, ``squats`` squats (down over 0.8 s to knees at 50 degrees, up over
    0.8 s, standing 0.6 s), then down once more over 0.8 s and held at the bottom ``hold_s``
    seconds; with ``back``, up again over 0.8 s and standing 0.6 s, else to the end. Returns
    it and the first frame of the hold."""
    rest, move = int(REST_S * FPS), int(MOVE_S * FPS)
    parts = [np.zeros(rest)]
    for _ in range(squats):
        parts += [_eased(move), _eased(move)[::-1], np.zeros(rest)]
    hold = sum(len(p) for p in parts) + move
    parts += [_eased(move), np.ones(int(hold_s * FPS))]
    if back:
        parts += [_eased(move)[::-1], np.zeros(rest)]
    return to_sequence(*(squat_pose(d) for d in np.concatenate(parts)), fps=FPS), hold


def _both(seq: PoseSequence, change: int, pad_s: float) -> tuple[list[int], list[int]]:
    """Each segment's repetitions by ``watch`` (the label changing at frame ``change``, the
    last frame held ``pad_s`` more) and by ``segment`` cut where ``watch`` cut."""
    watched = _watched(seq, (change,), pad_s=pad_s)
    padded = PoseSequence(
        np.concatenate([seq.positions, np.repeat(seq.positions[-1:], int(pad_s * FPS), 0)]),
        seq.joint_names,
        FPS,
    )
    cuts = [end / FPS for _, end, _ in watched[:-1]]
    return [r for *_, r in watched], _counts(padded, cuts)


@pytest.mark.parametrize("into_hold_s", [0.9, 2.4])
def test_a_squat_held_at_the_bottom_to_the_end_counts_none_in_watch_as_in_segment(
    into_hold_s: float,
) -> None:
    """By hand: the body goes down once (knees from 180 to 50 degrees) and stays down 6 s, to
    the end: it never comes back, a posture got into and held, no repetition (README: one
    far point between a start at one end of the movement and an end at the other, held still
    there); ``reps`` on it counts 0. The label changing 0.9 and 2.4 s into the hold: two
    segments, 0 and 0 in ``segment`` and now in ``watch`` (before: 1 and 0; ``watch``
    finished the first segment on frames beyond the cut that held no far point, and kept
    its far point)."""
    seq, hold = _squats_then_held(0, 6.0, back=False)
    assert count_repetitions(seq).count == 0
    watched, offline = _both(seq, hold + int(into_hold_s * FPS), 0.0)
    assert len(watched) == 2
    assert watched == offline == [0, 0]


@pytest.mark.parametrize("squats", [0, 2])
def test_a_squat_held_longer_than_watch_waits_counts_once(squats: int) -> None:
    """``squats`` squats, then one held at the bottom 12 s and up again: ``squats`` + 1
    repetitions by hand (``reps`` on the whole of it: 1 with no squat before; 2 with two,
    the long hold at the bottom taken for rest, a matter of the counter, not of the end of
    a stream). The label changing 0.9 s into the hold, ``watch``
    finishes the segment before the change while the hold goes on (the frames it has been
    sent beyond the cut hold no far point yet): the held squat is the segment after's, where
    the body comes back, as ``segment`` counts it: ``squats`` and 1 (before: ``squats`` + 1
    and 1, the held squat counted twice)."""
    seq, hold = _squats_then_held(squats, 12.0, back=True)
    if not squats:
        assert count_repetitions(seq).count == 1
    watched, offline = _both(seq, hold + int(0.9 * FPS), 2.0)
    assert watched == offline == [squats, 1]


def test_squats_then_one_held_to_the_end_add_up_alike() -> None:
    """Two squats, then down and held 20 s to the end: ``reps`` counts 3 (a far point cut off
    by the end counts beside whole ones; the posture rule is for a lone far point). Cut
    0.9 s into the hold, ``segment`` counts 3 and 0; ``watch``, which finishes the first
    segment while the hold goes on and cannot know it will not come back, leaves the held
    squat to the segment after, which counts it when the stream ends in the hold: 2 and 1,
    3 in all as ``segment``."""
    seq, hold = _squats_then_held(2, 20.0, back=False)
    assert count_repetitions(seq).count == 3
    watched, offline = _both(seq, hold + int(0.9 * FPS), 0.0)
    assert offline == [3, 0] and watched == [2, 1]
