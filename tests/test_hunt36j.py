"""Hunt 36j: a repetition held at its far point through a cut between two segments (the label
changing mid-hold) counts once, in one of the two segments, as the whole recording counts it."""

from __future__ import annotations

import numpy as np
import pytest

import cbr.segmentation as seg
from cbr.segmentation import counted_segments
from features.datasets import Clip
from features.poses import PoseSequence
from features.repetitions import count_repetitions, movement_signals
from tests.bodies import squat_pose, to_sequence
from tests.moves import clip
from tests.test_repetitions import FPS, _arms_raised_and_held
from tests.test_segment import _fit, _NeverUnknown

REST_S, MOVE_S, HOLD_S = 0.6, 0.8, 3.0
HOLD_FROM_S = REST_S + MOVE_S  # the hold: 1.4 s to 4.4 s


def _eased(n: int) -> np.ndarray:
    """0 -> 1 over ``n`` frames (half a cosine)."""
    return 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, n)))


def _held_squats(holds_s: tuple[float, ...] = (HOLD_S,)) -> PoseSequence:
    """Standing 0.6 s, then per entry of ``holds_s`` one squat: down over 0.8 s, held at the
    bottom that many seconds, up over 0.8 s, 0.6 s of standing (one repetition each)."""
    rest, move = int(REST_S * FPS), int(MOVE_S * FPS)
    parts = [np.zeros(rest)]
    for hold in holds_s:
        parts += [_eased(move), np.ones(int(hold * FPS)), _eased(move)[::-1], np.zeros(rest)]
    return to_sequence(*(squat_pose(d) for d in np.concatenate(parts)), fps=FPS)


def _counts(seq: PoseSequence, cuts_s: list[float]) -> list[int]:
    """Each segment's repetitions, ``seq`` cut at ``cuts_s`` seconds, as ``segment`` counts
    them (:func:`cbr.segmentation.counted_segments`, which its ``finish`` calls)."""
    edges = [0, *(int(round(t * seq.fps)) for t in cuts_s), seq.n_frames]
    bounds = list(zip(edges[:-1], edges[1:], strict=True))
    return [len(r) for r in counted_segments(movement_signals(seq), bounds, seq.n_frames)]


CLIPS = {
    "squat held at the bottom": lambda: _held_squats(),
    "arms held raised": lambda: _arms_raised_and_held(HOLD_S, lowered=True),
}


@pytest.mark.parametrize("clip", sorted(CLIPS))
@pytest.mark.parametrize("into_hold_s", [0.6, 1.5, 2.4])
def test_a_repetition_cut_in_its_hold_counts_once(clip: str, into_hold_s: float) -> None:
    """Down (or up), held 3 s, back, at rest: one repetition by construction, and the whole
    recording counts 1. Cut 0.6, 1.5 and 2.4 s into the hold (1.0 to 2.6 s from the ends of
    the way there and back), the segment after the cut counts it, the one before does not:
    the movement turns back beyond the cut. Before, 1 and 1: each segment's far point lay
    mid-way along its part of the hold, neither at the cut."""
    seq = CLIPS[clip]()
    assert count_repetitions(seq).count == 1
    assert _counts(seq, [HOLD_FROM_S + into_hold_s]) == [0, 1]


@pytest.mark.parametrize("clip", sorted(CLIPS))
def test_a_fragment_within_the_hold_counts_none(clip: str) -> None:
    """Cut twice in the hold, 1 s apart (1.9 and 2.9 s): the fragment is all hold. Its
    repetition is counted once, by the last segment, where the movement comes back; before,
    once in each of the three."""
    assert _counts(CLIPS[clip](), [HOLD_FROM_S + 0.5, HOLD_FROM_S + 1.5]) == [0, 0, 1]


def test_two_held_squats_cut_at_rest_and_in_the_second_hold() -> None:
    """Two squats, each held 1 s at the bottom (down 0.6-1.4 s, held to 2.4 s, up by 3.2 s,
    standing to 3.8 s; down by 4.6 s, held to 5.6 s, up by 6.4 s, standing to 7.0 s). Cut in
    the standing between them (3.5 s): one in each segment, as before. Cut in the second
    one's hold (5.1 s): the first segment keeps the first squat and the second counts the
    second, once (before: 2 and 1)."""
    seq = _held_squats((1.0, 1.0))
    assert count_repetitions(seq).count == 2
    assert _counts(seq, [3.5]) == [1, 1]
    assert _counts(seq, [5.1]) == [1, 1]


def test_segment_counts_a_squat_held_across_its_change_of_label_once(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The whole ``segment`` path (windows solved by a case base of synthetic squats and arm
    abductions, decoded, counted, given as ``--json`` gives them), the squat held 3 s and the
    decoded labels made to change 1.5 s into the hold (block 29: frame 87 of 174), as a
    classifier that saw something else in the hold would: two segments, counts 0 and 1
    (before: 1 and 1, two repetitions where the recording holds one)."""
    names = ("squat", "arm_abduction")
    clf = _fit([Clip(clip(n).with_metadata(label=n, subject="s"), n, "s", {}) for n in names])
    decoded = seg.decode_activities
    cut_block = int(round((HOLD_FROM_S + 1.5) / seg.BLOCK_S))

    def change_in_the_hold(*args: object, **kwargs: object) -> tuple[np.ndarray, np.ndarray]:
        votes, path = decoded(*args, **kwargs)  # type: ignore[arg-type]
        path[:cut_block], path[cut_block:] = 0, 1
        return votes, path

    monkeypatch.setattr(seg, "decode_activities", change_in_the_hold)
    doc = seg.segment(clf, _held_squats(), _NeverUnknown()).to_dict()
    spans = [(s["start_frame"], s["end_frame"], s["count"]) for s in doc["segments"]]
    assert spans == [(0, 87, 0), (87, 174, 1)]
