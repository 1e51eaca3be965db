"""Hunt 36l: ``watch`` (the live segmenter) counts a repetition held at its far point through
a change of label once, in the segment where the movement comes back, as ``segment`` does
since 36j (tests/test_hunt36j.py)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from features.poses import PoseSequence
from features.repetitions import count_repetitions
from tests.test_hunt36j import HOLD_FROM_S, _held_squats
from tests.test_live import _Scripted
from tests.test_repetitions import FPS, _arms_raised_and_held

LABELS = np.array(["a", "b"])
PAD_S = 2.0  # standing on after the recording: the change settles before the stream ends


class _Changing(_Scripted):
    """Windows voting for activity 0, then 1, 0, ... by turns, changing where their centre
    passes each frame of ``changes`` (the label a classifier that saw something else in the
    hold would give)."""

    changes: tuple[int, ...] = ()

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        centre = n - self.window / 2
        return np.eye(2)[sum(centre >= c for c in self.changes) % 2], 0.0


def _live_segments(
    frames: np.ndarray, fps: float, changes: tuple[int, ...] = (), seen: np.ndarray | None = None
) -> list:
    """The segments ``watch``'s live segmenter gives ``frames`` pushed one by one (with their
    joints' confidence ``seen``, as ``watch`` pushes a video's), one label ("a") throughout
    but for changes at ``changes``, the stream ending with the last frame."""
    clf = SimpleNamespace(classes_=LABELS, case_base_=SimpleNamespace(labels=LABELS))
    live = _Changing(clf, fps, judge=SimpleNamespace())
    live.changes = changes
    out = []
    for i, frame in enumerate(frames):
        out += live.push(frame) if seen is None else live.push(frame, seen[i])
    out += live.finish()
    return out


def _watched(seq: PoseSequence, changes: tuple[int, ...], pad_s: float = PAD_S) -> list:
    """(start_frame, end_frame, repetitions) of each segment ``watch`` gives ``seq`` (its last
    frame held ``pad_s`` more), the label changing at ``changes``."""
    frames = np.concatenate([seq.positions, np.repeat(seq.positions[-1:], int(pad_s * seq.fps), 0)])
    out = _live_segments(frames, seq.fps, changes)
    return [(s.start_frame, s.end_frame, s.repetitions) for s in out]


HOLD = (int(HOLD_FROM_S * FPS), int((HOLD_FROM_S + 3.0) * FPS))  # frames 42-132
CLIPS = {
    "squat held at the bottom": lambda: _held_squats(),
    "arms held raised": lambda: _arms_raised_and_held(3.0, lowered=True),
}


@pytest.mark.parametrize("clip", sorted(CLIPS))
@pytest.mark.parametrize("into_hold_s", [0.9, 1.5, 2.4])
def test_watch_counts_a_repetition_cut_in_its_hold_once(clip: str, into_hold_s: float) -> None:
    """Down (or up) 0.6-1.4 s, held 3 s, back by 5.2 s, standing: one repetition, as the
    whole recording counts. The label made to change 0.9, 1.5 (as tests/test_hunt36j.py
    forces it: frame 87) and 2.4 s into the hold: two segments, cut in the hold; the one
    before has not seen the movement come back (0), the one after has (1). Before, 1 and 1
    (with the cut past 0.9 s into the hold): each segment's far point lay mid-way along its
    part of the hold, neither at the cut."""
    seq = CLIPS[clip]()
    assert count_repetitions(seq).count == 1
    (a, cut, first), (cut_too, _, second) = _watched(seq, (int((HOLD_FROM_S + into_hold_s) * FPS),))
    assert a == 0 and cut == cut_too and HOLD[0] < cut < HOLD[1]
    assert (first, second) == (0, 1)


def test_a_fragment_all_hold_passes_the_hold_on() -> None:
    """A squat held 5 s (frames 42-192), the label changing 1.0 s and 3.0 s into the hold
    (frames 72 and 132): three segments, the middle one all hold. The squat counts once, in
    the last, where it comes back: 0, 0, 1 (before: 1, 0, 1)."""
    seq = _held_squats((5.0,))
    segments = _watched(seq, (72, 132))
    assert len(segments) == 3 and 42 < segments[0][1] < segments[1][1] < 192
    assert [r for *_, r in segments] == [0, 0, 1]


def test_two_held_squats_cut_in_the_second_hold() -> None:
    """Two squats each held 1 s (the second held 4.6-5.6 s: frames 138-168), the label
    changing at 5.1 s (frame 153): the first segment counts the first squat, the second the
    second: 1 and 1 (before: 2 and 1, three where the recording holds two). Cut in the
    standing between them (3.5 s), 1 and 1 as before."""
    seq = _held_squats((1.0, 1.0))
    assert count_repetitions(seq).count == 2
    held = _watched(seq, (153,))
    assert 138 < held[0][1] < 168 and [r for *_, r in held] == [1, 1]
    assert [r for *_, r in _watched(seq, (105,))] == [1, 1]


def test_a_segment_finished_while_the_stream_runs_on_leaves_the_held_squat_to_the_next() -> None:
    """The held squat, the label changing 1.5 s into the hold (frame 87), then 20 s more of
    standing: the first segment is finished, and its line printed, while the stream runs on
    (the decoders settle the change some seconds after it), on what has been pushed by then:
    0, and the segment after counts the squat (1). Before, 1 and 1."""
    clf = SimpleNamespace(classes_=LABELS, case_base_=SimpleNamespace(labels=LABELS))
    live = _Changing(clf, FPS, judge=SimpleNamespace())
    live.changes = (87,)
    seq = _held_squats()
    frames = np.concatenate([seq.positions, np.repeat(seq.positions[-1:], int(20 * FPS), 0)])
    pushed = []
    for frame in frames:
        pushed += live.push(frame)
    (first,) = pushed
    assert HOLD[0] < first.end_frame < HOLD[1] and first.repetitions == 0
    (last,) = live.finish()
    assert last.start_frame == first.end_frame and last.repetitions == 1
