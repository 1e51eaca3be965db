"""Hunt 37b: a repetition shared by two neighbouring segments counts once, in ``segment`` and
in ``watch``: a squat whose hold dips (rises 20 degrees or more and sinks again) across a
change of label, and a squat the person is lost from view in before coming up."""

from __future__ import annotations

import numpy as np
import pytest

import cbr.segmentation as seg
from features.datasets import Clip
from features.poses import PoseSequence
from features.repetitions import count_repetitions
from tests.bodies import squat_pose, to_sequence
from tests.moves import clip
from tests.test_hunt36j import MOVE_S, REST_S, _counts, _eased
from tests.test_hunt36l import _live_segments, _watched
from tests.test_repetitions import FPS
from tests.test_segment import _fit, _NeverUnknown

DIP_S = 0.4  # up to the top of the dip, and as long down again
DIP_AT_S = REST_S + MOVE_S + 1.0 + DIP_S  # the top of the dip: 2.8 s (frame 84)


def _dipped_squat(dip: float) -> PoseSequence:
    """Standing 0.6 s, down over 0.8 s to the bottom (knees at 50 degrees), held 1 s, up
    ``dip`` of the way over 0.4 s, down again over 0.4 s to 0.95 of the depth, held 1 s, up
    over 0.8 s, standing 0.6 s: one squat whose hold dips once."""
    rest, move, hold, dip_n = (int(t * FPS) for t in (REST_S, MOVE_S, 1.0, DIP_S))
    depth = np.concatenate([
        np.zeros(rest), _eased(move), np.ones(hold), 1.0 - dip * _eased(dip_n),
        0.95 - (dip - 0.05) * _eased(dip_n)[::-1], np.full(hold, 0.95),
        0.95 * _eased(move)[::-1], np.zeros(rest),
    ])  # fmt: skip
    return to_sequence(*(squat_pose(d) for d in depth), fps=FPS)


@pytest.mark.parametrize("dip", [0.2, 0.3])
@pytest.mark.parametrize("cut_s", [2.6, DIP_AT_S, 3.0])
def test_a_squat_whose_hold_dips_across_a_cut_counts_once(dip: float, cut_s: float) -> None:
    """By hand: at the bottom the knees are at 180 - 130 = 50 degrees; the dip straightens
    them by 130 x 0.2 = 26 (0.3: 39) degrees, more than MIN_EXCURSION_RAD (15), and sinks to
    56.5 degrees; then the squat comes up to 180. The dip gives back 20 % (30 %) of the
    squat's height, less than RETURN_SHARE (40 %): one repetition, as ``reps`` counts the
    whole recording. Cut on the dip's way up, at its top and on its way down, it counts once,
    in the segment after (where the movement comes back), as a squat held across a cut.
    Before, 1 and 1: each side turned back 15 degrees or more, neither was "held"."""
    seq = _dipped_squat(dip)
    assert count_repetitions(seq).count == 1
    assert _counts(seq, [cut_s]) == [0, 1]


@pytest.mark.parametrize("dip", [0.2, 0.3])
@pytest.mark.parametrize("cut_s", [2.6, DIP_AT_S, 3.0])
def test_watch_counts_a_squat_whose_hold_dips_across_a_change_once(
    dip: float, cut_s: float
) -> None:
    """The same squats streamed through ``watch``, the label changing at the same frames:
    two segments, 0 and 1, each line printed once (before: 1 and 1)."""
    segments = _watched(_dipped_squat(dip), (int(round(cut_s * FPS)),))
    assert len(segments) == 2
    assert [r for *_, r in segments] == [0, 1]


def _lost_in_a_squat(hold_s: float) -> tuple[PoseSequence, int]:
    """Standing 0.6 s, down over 0.8 s to the bottom, held ``hold_s``; then 1.5 s in which no
    joint is seen (every coordinate NaN: the person out of view), then 3 s standing again.
    Returns it and the first frame out of view."""
    rest, move, hold = int(REST_S * FPS), int(MOVE_S * FPS), int(hold_s * FPS)
    seen = np.concatenate([np.zeros(rest), _eased(move), np.ones(hold)])
    depth = np.concatenate([seen, np.zeros(int(4.5 * FPS))])
    seq = to_sequence(*(squat_pose(d) for d in depth), fps=FPS)
    positions = seq.positions.copy()
    positions[len(seen) : len(seen) + int(1.5 * FPS)] = np.nan
    return PoseSequence(positions, seq.joint_names, FPS), len(seen)


HOLDS_S = [0.0, 0.3, 1.0]


# on one xdist worker: the module's squat_or_arms made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt37b")


@pytest.fixture(scope="module")
def squat_or_arms() -> object:
    """A case base of the synthetic squat and arm abduction, as tests/test_hunt36j.py fits."""
    names = ("squat", "arm_abduction")
    return _fit([Clip(clip(n).with_metadata(label=n, subject="s"), n, "s", {}) for n in names])


@pytest.mark.parametrize("hold_s", HOLDS_S)
def test_segment_keeps_a_squat_lost_from_view_at_the_bottom(
    squat_or_arms: object, hold_s: float
) -> None:
    """By hand: one squat down (knees from 180 to 50 degrees), held 0, 0.3 or 1 s, then
    nobody in view for 1.5 s, then the person standing: one repetition (``reps`` counts 1 on
    the whole recording), done in the segment before the stretch with nobody in view, which
    counts none by design. Counted as one activity going on across the stretch (hunt 51b:
    the segments' counts with no activities told apart), the squat's segment 1, the stretch
    0, the rest 0. Before: 0 at 0 and 1 s (left to the stretch at the cut, or taken for a
    posture got into and held up to it). ``segment`` itself calls the standing after the
    stretch arm abduction (the start posture of both activities this case base holds):
    another activity, which does not finish the squat, so 0 there (hunt 51b: a squat's way
    down, then nobody in view, then other exercises, counts none)."""
    from features.repetitions import movement_signals

    seq, lost = _lost_in_a_squat(hold_s)
    assert count_repetitions(seq).count == 1
    found = seg.segment(squat_or_arms, seq, _NeverUnknown()).segments
    nobody = [i for i, s in enumerate(found) if s.explanation == seg.NOBODY]
    assert len(nobody) == 1 and found[nobody[0]].start_frame == lost
    bounds = [(s.start_frame, s.end_frame) for s in found]
    unseen = [s.explanation == seg.NOBODY for s in found]
    alike = seg.counted_segments(movement_signals(seq), bounds, seq.n_frames, unseen)
    assert [len(r) for r in alike[: nobody[0] + 1]] == [1] * nobody[0] + [0]
    assert sum(len(r) for r in alike) == 1
    assert [s.label for s in found] == ["squat", None, "arm_abduction"]
    assert sum(len(s.repetitions) for s in found) == 0


@pytest.mark.parametrize("hold_s", HOLDS_S)
def test_watch_keeps_a_squat_lost_from_view_at_the_bottom(hold_s: float) -> None:
    """The same streamed through ``watch`` (one label throughout): the squat counts once,
    nobody in view 0. Before: 0 at 0 and 0.3 s (left to the segment with nobody in view).
    Since hunt 51b, a far point the person is lost at (held at the bottom for 0 or 0.3 s:
    the hold up to the cut) is counted by the segment where the person is seen again, on
    the frames from its repetition on, across the stretch (``watch`` cannot tell when the
    person is lost whether they come back: the way down of a squat, the person lost for
    good, counts none); one held longer, its far point in its own segment, there."""
    seq, lost = _lost_in_a_squat(hold_s)
    out = _live_segments(seq.positions, seq.fps)
    got = [(s.start_frame, s.label, s.repetitions) for s in out]
    assert [g[:2] for g in got] == [(0, "a"), (lost, None), (lost + int(1.5 * FPS), "a")]
    assert got[1][2] == 0 and got[0][2] + got[2][2] == 1
