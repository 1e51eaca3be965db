"""Hunt 37h: a posture got into after a cut between two segments and held to the
recording's end (a side plank after another exercise) is no repetition in its segment, as
it is none in a clip of its own."""

from __future__ import annotations

import numpy as np
import pytest

from features.poses import PoseSequence
from features.repetitions import count_repetitions
from tests.bodies import squat_pose, to_sequence
from tests.test_hunt36j import MOVE_S, REST_S, _counts, _eased
from tests.test_hunt36l import _watched
from tests.test_repetitions import FPS, _raise_arms

SQUATS_END_S = 2 * (MOVE_S + MOVE_S + REST_S) + REST_S  # 0.6 s standing, two squats: 5.0 s
SAG_S, STILL_S = 3.0, 1.0


def _arms_held(sag: float, wobble: float = 0.0) -> np.ndarray:
    """Both arms' angle (degrees) per frame: raised sideways to 90 degrees over 0.8 s, held
    4 s sinking ``sag`` degrees over its first 3 s, still over the last 1 s; with ``wobble``,
    0.3 s into that last second they dip that much over 0.2 s and come back over 0.2 s."""
    move, wob = int(MOVE_S * FPS), int(0.2 * FPS)
    still = np.full(int(STILL_S * FPS), 90.0 - sag)
    at = int(0.3 * FPS)
    still[at : at + 2 * wob] -= wobble * np.concatenate([_eased(wob), _eased(wob)[::-1]])
    return np.concatenate([90.0 * _eased(move), 90.0 - sag * _eased(int(SAG_S * FPS)), still])


def _squats_then_arms_held(sag: float, wobble: float = 0.0) -> PoseSequence:
    """Standing 0.6 s, two squats (down over 0.8 s to knees at 50 degrees, up over 0.8 s,
    0.6 s standing: 5.0 s in all); then, standing, both arms raised sideways to 90 degrees
    over 0.8 s and held for 4 s, sinking ``sag`` degrees over its first 3 s (a side plank's
    supporting shoulder sags as it is held), still over the last 1 s, to the end."""
    rest, move = int(REST_S * FPS), int(MOVE_S * FPS)
    depth = np.concatenate([np.zeros(rest), *[[*_eased(move), *_eased(move)[::-1],
                                               *np.zeros(rest)] for _ in range(2)]])  # fmt: skip
    arms = _arms_held(sag, wobble)
    frames = [squat_pose(d) for d in depth]
    frames += [_raise_arms(squat_pose(0.0), a, a) for a in arms]
    return to_sequence(*frames, fps=FPS)


@pytest.mark.parametrize("sag", [0.0, 25.0])
def test_a_posture_got_into_after_a_cut_and_held_to_the_end_counts_none(sag: float) -> None:
    """By hand: two squats (0 -> 50 degrees at the knees and back, twice), then the arms go
    out once to 90 degrees and stay out to the end: 2 repetitions, then none (the arms never
    come back). With the sag (25 degrees over 3 s, 3.3 degrees in any 0.4 s, less than
    MIN_EXCURSION_RAD's 15) the arms' far point, at the top of the raise, falls back 25
    degrees within the hold, more than a repetition's return: a whole far point. On the
    arms alone, as a clip of their own, 0 either way (the side plank's rule: the clip starts
    at rest and ends in the far posture, still). Cut where the squats end (5.0 s), the
    segment after counted 1 with the sag (the rule judged only a segment starting where the
    recording does, or after a segment with no far point); now 0, and the squats' 2."""
    seq = _squats_then_arms_held(sag)
    cut = int(round(SQUATS_END_S * FPS))
    assert count_repetitions(seq.slice_frames(cut, None)).count == 0
    assert count_repetitions(seq.slice_frames(0, cut)).count == 2
    assert _counts(seq, [SQUATS_END_S]) == [2, 0]


def test_watch_counts_no_repetition_in_a_posture_got_into_after_a_change() -> None:
    """The same recording with the sag streamed through ``watch``, the label changing where
    the squats end: two segments, 2 and 0, as ``segment`` (before: 2 and 1)."""
    seq = _squats_then_arms_held(25.0)
    segments = _watched(seq, (int(round(SQUATS_END_S * FPS)),))
    assert len(segments) == 2
    assert [r for *_, r in segments] == [2, 0]


def test_a_repetition_after_a_cut_still_counts() -> None:
    """The arms raised to 90 degrees and lowered again over 0.8 s each, then 1 s standing,
    after the squats: one repetition after the cut, not a posture held (the arms come
    back): 2 and 1."""
    rest, move = int(REST_S * FPS), int(MOVE_S * FPS)
    seq = _squats_then_arms_held(0.0)
    cut = int(round(SQUATS_END_S * FPS))
    arms = np.concatenate([90.0 * _eased(move), 90.0 * _eased(move)[::-1], np.zeros(rest + 10)])
    tail = to_sequence(*(_raise_arms(squat_pose(0.0), a, a) for a in arms), fps=FPS)
    both = PoseSequence(np.concatenate([seq.positions[:cut], tail.positions]), seq.joint_names, FPS)
    assert _counts(both, [SQUATS_END_S]) == [2, 1]


def test_a_wobble_in_the_hold_is_no_return_from_the_far_point() -> None:
    """Arms raised to 90 degrees and held sagging 25 degrees, as above, with a wobble near
    the end: both arms dip 12 degrees and come back within 0.4 s (the movement line, about
    one arm's angle, moves some 20 degrees in all over 0.4 s there, smoothed: more than
    MIN_EXCURSION_RAD's 15, but spans 12, less), then 0.3 s still. By hand no repetition:
    the arms went out once and stayed. Before, 1: the hold was read as starting after the
    wobble, and the 25 degrees of sag before it as the far point's return (a re-encoded
    side plank in a joined video: `segment` and `reps` on it counted 1, the original clip
    0). Alone and after the squats' cut: 0; the squats 2."""
    arms = _arms_held(25.0, wobble=12.0)
    body = squat_pose(0.0)
    rest = [body] * int(REST_S * FPS)
    alone = to_sequence(*rest, *(_raise_arms(body, a, a) for a in arms), fps=FPS)
    assert count_repetitions(alone).count == 0
    assert _counts(_squats_then_arms_held(25.0, wobble=12.0), [SQUATS_END_S]) == [2, 0]
